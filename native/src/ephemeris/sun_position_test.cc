#include "sunlapse/ephemeris/sun_position.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace sunlapse {
namespace {

constexpr double kDeg = M_PI / 180.0;

double AzimuthDiff(double a, double b) {
  return std::abs(std::remainder(a - b, 360.0));
}

// NREL SPA's published example (Reda & Andreas, NREL/TP-560-34302, table A4.1):
// 2003-10-17 12:30:30 local time at UTC-7, 39.742476 N, -105.1786 E, 1830.14 m,
// 820 mbar, 11 C, delta-T 67 s -> topocentric zenith 50.11162, azimuth
// 194.34024 degrees.
TEST(SunPosition, MatchesSpaPublishedExample) {
  SunPositionOptions o;
  o.elevation_m = 1830.14;
  o.pressure_hpa = 820;
  o.temperature_c = 11;
  const SunPosition s =
      SunPositionAt({2003, 10, 17, 19, 30, 30.0}, 39.742476, -105.1786, o);
  EXPECT_NEAR(s.zenith_deg, 50.11162, 0.01);
  EXPECT_NEAR(s.azimuth_deg, 194.34024, 0.01);
}

// An independent low-precision solar position (the Astronomical Almanac's
// formula, good to about 0.01 deg for 1950-2050), geometric, no refraction.
void LowPrecision(const UtcTime& t, double lat, double lon, double* zenith,
                  double* azimuth) {
  auto days_from_civil = [](int y, int m, int d) {
    y -= m <= 2;
    const int era = (y >= 0 ? y : y - 399) / 400;
    const int yoe = y - era * 400;
    const int doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    return era * 146097 + doe - 719468;  // days since 1970-01-01
  };
  const double n = days_from_civil(t.year, t.month, t.day) - 10957.5 +
                   (t.hour + t.minute / 60.0 + t.second / 3600.0) / 24.0;
  const double L = 280.460 + 0.9856474 * n,
               g = (357.528 + 0.9856003 * n) * kDeg;
  const double lambda =
      (L + 1.915 * std::sin(g) + 0.020 * std::sin(2 * g)) * kDeg;
  const double eps = (23.439 - 0.0000004 * n) * kDeg;
  const double ra =
      std::atan2(std::cos(eps) * std::sin(lambda), std::cos(lambda));
  const double dec = std::asin(std::sin(eps) * std::sin(lambda));
  const double gmst_deg = 280.46061837 + 360.98564736629 * n;
  const double H = gmst_deg * kDeg + lon * kDeg - ra;
  const double phi = lat * kDeg;
  const double cos_z = std::sin(phi) * std::sin(dec) +
                       std::cos(phi) * std::cos(dec) * std::cos(H);
  *zenith = std::acos(cos_z) / kDeg;
  const double az = std::atan2(-std::sin(H) * std::cos(dec),
                               std::cos(phi) * std::sin(dec) -
                                   std::sin(phi) * std::cos(dec) * std::cos(H));
  *azimuth = std::fmod(az / kDeg + 360.0, 360.0);
}

struct Case {
  UtcTime t;
  double lat, lon;
};

class SunPositionCrossCheck : public ::testing::TestWithParam<Case> {};

TEST_P(SunPositionCrossCheck, AgreesWithIndependentFormula) {
  const Case c = GetParam();
  SunPositionOptions o;
  o.pressure_hpa = 0;  // geometric, like the reference formula
  const SunPosition s = SunPositionAt(c.t, c.lat, c.lon, o);
  double z, a;
  LowPrecision(c.t, c.lat, c.lon, &z, &a);
  EXPECT_NEAR(s.zenith_deg, z, 0.03);
  EXPECT_LT(AzimuthDiff(s.azimuth_deg, a),
            0.03 / std::max(0.2, std::sin(z * kDeg)));
}

INSTANTIATE_TEST_SUITE_P(
    BothHemispheres, SunPositionCrossCheck,
    ::testing::Values(
        Case{{2024, 6, 21, 12, 0, 0}, 51.48, 0.0},      // London
        Case{{2024, 12, 21, 3, 0, 0}, -33.87, 151.21},  // Sydney
        Case{{2005, 1, 13, 10, 0, 0}, 43.3, 5.4},       // Marseille
        Case{{2010, 3, 20, 18, 0, 0}, -34.6, -58.4},    // Buenos Aires
        Case{{2031, 9, 1, 23, 45, 10}, 35.68, 139.69},  // Tokyo
        Case{{2019, 7, 4, 16, 20, 0}, -1.29, 36.82}));  // Nairobi

TEST(SunPosition, SouthernNoonSunIsInTheNorth) {
  // Sydney, around local solar noon (UTC+10:05 in solar time) in June.
  const SunPosition s = SunPositionAt({2024, 6, 21, 1, 55, 0}, -33.87, 151.21);
  EXPECT_LT(AzimuthDiff(s.azimuth_deg, 0.0), 5.0);
  EXPECT_NEAR(s.zenith_deg, 33.87 + 23.44, 0.5);
}

TEST(SunPosition, RefractionLiftsTheSunMostNearTheHorizon) {
  SunPositionOptions off;
  off.pressure_hpa = 0;
  // Marseille, 13 Jan 2005 around sunset and at noon.
  const UtcTime dusk{2005, 1, 13, 16, 0, 0}, noon{2005, 1, 13, 11, 30, 0};
  const double lift_dusk = SunPositionAt(dusk, 43.3, 5.4, off).zenith_deg -
                           SunPositionAt(dusk, 43.3, 5.4).zenith_deg;
  const double lift_noon = SunPositionAt(noon, 43.3, 5.4, off).zenith_deg -
                           SunPositionAt(noon, 43.3, 5.4).zenith_deg;
  EXPECT_GT(lift_dusk, 0.1);
  EXPECT_GT(lift_noon, 0.0);
  EXPECT_LT(lift_noon, 0.05);
}

TEST(SunPosition, DirectionFollowsDesignConvention) {
  double d[3];
  SunDirection(90, 90, 0, d);  // on the horizon, due east: +X
  EXPECT_NEAR(d[0], 1, 1e-12);
  EXPECT_NEAR(d[1], 0, 1e-12);
  SunDirection(0, 123, 0, d);  // overhead: +Z
  EXPECT_NEAR(d[2], 1, 1e-12);
  SunDirection(60, 0, 90, d);  // north, scene turned 90 deg: toward +X
  EXPECT_NEAR(d[0], std::sin(60 * kDeg), 1e-12);
}

TEST(SunPosition, RejectsBadInput) {
  EXPECT_THROW(SunPositionAt({2024, 2, 30, 0, 0, 0}, 0, 0),
               std::invalid_argument);
  EXPECT_THROW(SunPositionAt({2024, 1, 1, 0, 0, 0}, 91, 0),
               std::invalid_argument);
  SunPositionOptions o;
  o.dut1_s = 3;
  EXPECT_THROW(SunPositionAt({2024, 1, 1, 0, 0, 0}, 0, 0, o),
               std::invalid_argument);
}

}  // namespace
}  // namespace sunlapse
