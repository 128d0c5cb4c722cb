#include "sunlapse/ephemeris/sun_position.h"
#include "sunlapse/common/require.h"

#include <erfa.h>

#include "sunlapse/common/angles.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace sunlapse {
namespace {

constexpr double kDeg = M_PI / 180.0;

}  // namespace

void SunPositionOptions::Check() const {
  Require(std::isfinite(elevation_m) && elevation_m > -500 && elevation_m < 1e5,
          "elevation_m must be in (-500, 100000) m");
  Require(
      std::isfinite(pressure_hpa) && pressure_hpa >= 0 && pressure_hpa < 2000,
      "pressure_hpa must be in [0, 2000)");
  Require(std::isfinite(temperature_c) && temperature_c > -150 &&
              temperature_c < 200,
          "temperature_c must be in (-150, 200)");
  Require(std::isfinite(relative_humidity) && relative_humidity >= 0 &&
              relative_humidity <= 1,
          "relative_humidity must be in [0, 1]");
  Require(std::isfinite(dut1_s) && std::abs(dut1_s) < 1.0,
          "dut1_s must be in (-1, 1) s");
}

SunPosition SunPositionAt(const UtcTime& utc, double latitude_deg,
                          double longitude_deg,
                          const SunPositionOptions& options) {
  options.Check();
  Require(std::isfinite(latitude_deg) && std::abs(latitude_deg) <= 90,
          "latitude_deg must be in [-90, 90]");
  Require(std::isfinite(longitude_deg) && std::abs(longitude_deg) <= 360,
          "longitude_deg must be in [-360, 360]");
  double utc1, utc2;
  const int sec_int = static_cast<int>(std::floor(utc.second));
  Require(utc.second >= 0 && utc.second < 61, "second must be in [0, 61)");
  if (eraDtf2d("UTC", utc.year, utc.month, utc.day, utc.hour, utc.minute,
               utc.second, &utc1, &utc2) < 0) {
    throw std::invalid_argument(
        "utc: invalid date or time " + std::to_string(utc.year) + "-" +
        std::to_string(utc.month) + "-" + std::to_string(utc.day) + " " +
        std::to_string(utc.hour) + ":" + std::to_string(utc.minute) + ":" +
        std::to_string(sec_int));
  }
  eraASTROM astrom;
  double eo;
  // Status +1 ("dubious year": outside the leap-second table) still gives a
  // usable answer; TT-UTC error of a few seconds moves the Sun < 0.001 deg.
  const int status = eraApco13(utc1, utc2, options.dut1_s, longitude_deg * kDeg,
                               latitude_deg * kDeg, options.elevation_m, 0.0,
                               0.0, options.pressure_hpa, options.temperature_c,
                               options.relative_humidity, 0.55, &astrom, &eo);
  Require(status >= 0, "utc: ERFA rejected the date");

  // Direction from the observer to the Sun: minus the observer's heliocentric
  // direction (apco13 includes the observer's offset from the geocentre, so
  // this is topocentric and carries the solar parallax). The Sun moves only
  // metres during the light time, so no light-time iteration is needed, and
  // light deflection by the Sun does not apply to the Sun itself.
  double natural[3] = {-astrom.eh[0], -astrom.eh[1], -astrom.eh[2]};
  double proper[3];
  eraAb(natural, astrom.v, astrom.em, astrom.bm1, proper);  // aberration
  double cirs[3];
  eraRxp(astrom.bpn, proper, cirs);  // bias-precession-nutation -> CIRS
  double ri, di;
  eraC2s(cirs, &ri, &di);
  double aob, zob, hob, dob, rob;
  eraAtioq(eraAnp(ri), di, &astrom, &aob, &zob, &hob, &dob, &rob);
  SunPosition out;
  out.zenith_deg = zob / kDeg;
  out.azimuth_deg = WrapAzimuthDeg(aob / kDeg);
  return out;
}

void SunDirection(double zenith_deg, double azimuth_deg,
                  double north_offset_deg, double out_xyz[3]) {
  const Eigen::Vector3d d = SunInWorldFromAngles(
      zenith_deg, AzimuthWorldFromGeographic(azimuth_deg, north_offset_deg));
  out_xyz[0] = d.x();
  out_xyz[1] = d.y();
  out_xyz[2] = d.z();
}

}  // namespace sunlapse
