// The Sun's apparent topocentric position from time and place.
//
// Built on ERFA (the IAU SOFA algorithms): the Earth's heliocentric position
// and velocity (VSOP-based eraEpv00 inside eraApco13), annual aberration,
// precession-nutation, Earth rotation, polar motion left at zero, and the
// refraction model of eraRefco. Angles follow docs/design.md §4: zenith from +Z
// (up), azimuth clockwise from north toward east, degrees.
#pragma once

namespace sunlapse {

// A civil UTC instant.
struct UtcTime {
  int year = 2000;
  int month = 1;
  int day = 1;
  int hour = 12;
  int minute = 0;
  double second = 0.0;  // may carry the fraction
};

struct SunPositionOptions {
  // Observer's height above the ellipsoid, metres.
  double elevation_m = 0.0;
  // Air pressure at the observer, hPa (= mbar). 0 turns refraction off.
  double pressure_hpa = 1013.25;
  // Air temperature, degrees Celsius.
  double temperature_c = 15.0;
  // Relative humidity, 0..1.
  double relative_humidity = 0.0;
  // UT1 - UTC in seconds (|dut1| < 1 s; 0 when unknown costs < 0.004 deg).
  double dut1_s = 0.0;

  // Throws std::invalid_argument naming the bad field.
  void Check() const;
};

struct SunPosition {
  double zenith_deg = 0.0;   // observed, refraction included if enabled
  double azimuth_deg = 0.0;  // [0, 360), clockwise from north
};

// latitude_deg: north positive; longitude_deg: east positive.
// Throws std::invalid_argument for an invalid date or place.
SunPosition SunPositionAt(const UtcTime& utc, double latitude_deg,
                          double longitude_deg,
                          const SunPositionOptions& options = {});

// Unit vector toward the Sun in a world frame whose +Y is turned from north
// by north_offset_deg (as Blender's Sun Position add-on):
// (sin z sin a', sin z cos a', cos z), a' = azimuth + north_offset.
void SunDirection(double zenith_deg, double azimuth_deg,
                  double north_offset_deg, double out_xyz[3]);

}  // namespace sunlapse
