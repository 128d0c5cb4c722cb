#include "sunlapse/common/angles.h"

#include <gtest/gtest.h>

namespace sunlapse {
namespace {

TEST(SunInWorldFromAngles, PointsAlongTheWorldAxes) {
  // Overhead: +Z whatever the azimuth.
  EXPECT_LT((SunInWorldFromAngles(0, 123) - Eigen::Vector3d(0, 0, 1)).norm(),
            1e-12);
  // On the horizon: north is +Y, east +X, south -Y, west -X.
  EXPECT_LT((SunInWorldFromAngles(90, 0) - Eigen::Vector3d(0, 1, 0)).norm(),
            1e-12);
  EXPECT_LT((SunInWorldFromAngles(90, 90) - Eigen::Vector3d(1, 0, 0)).norm(),
            1e-12);
  EXPECT_LT((SunInWorldFromAngles(90, 180) - Eigen::Vector3d(0, -1, 0)).norm(),
            1e-12);
  EXPECT_LT((SunInWorldFromAngles(90, 270) - Eigen::Vector3d(-1, 0, 0)).norm(),
            1e-12);
  // 60 deg from the zenith toward the north-east, of unit length.
  const Eigen::Vector3d d = SunInWorldFromAngles(60, 45);
  EXPECT_NEAR(d.norm(), 1.0, 1e-12);
  EXPECT_NEAR(d.z(), 0.5, 1e-12);
  EXPECT_NEAR(d.x(), d.y(), 1e-12);
  EXPECT_GT(d.x(), 0);
}

TEST(AnglesFromSunInWorld, InvertsSunInWorldFromAnglesAtAnyLength) {
  for (double zenith = 0.5; zenith < 180; zenith += 7.3) {
    for (double azimuth = 0; azimuth < 360; azimuth += 11.1) {
      double z = -1, a = -1;
      AnglesFromSunInWorld(3.7 * SunInWorldFromAngles(zenith, azimuth), &z, &a);
      EXPECT_NEAR(z, zenith, 1e-9);
      EXPECT_NEAR(a, azimuth, 1e-9) << "zenith " << zenith;
    }
  }
}

TEST(AnglesFromSunInWorld, WestIsBelow360AndStraightUpHasAzimuthZero) {
  double z, a;
  AnglesFromSunInWorld({-1, 1e-9, 0}, &z, &a);  // just north of west
  EXPECT_NEAR(a, 270, 1e-6);
  AnglesFromSunInWorld({-1e-9, 1, 0}, &z, &a);  // just west of north
  EXPECT_GE(a, 0.0);
  EXPECT_LT(a, 360.0);
  EXPECT_NEAR(a, 360, 1e-6);
  AnglesFromSunInWorld({0, 0, 2}, &z, &a);
  EXPECT_EQ(z, 0.0);
  EXPECT_EQ(a, 0.0);
}

TEST(AzimuthWorldFromGeographic, TurnsByTheNorthOffsetAndWraps) {
  // A scene turned 90 deg: true north lies along world +X.
  EXPECT_NEAR(AzimuthWorldFromGeographic(0, 90), 90, 1e-12);
  EXPECT_NEAR(AzimuthWorldFromGeographic(300, 90), 30, 1e-12);
  EXPECT_NEAR(AzimuthWorldFromGeographic(10, -30), 340, 1e-12);
  EXPECT_NEAR(AzimuthGeographicFromWorld(30, 90), 300, 1e-12);
  EXPECT_NEAR(AzimuthGeographicFromWorld(340, -30), 10, 1e-12);
  for (double geo = 0; geo < 360; geo += 13.7) {
    for (double offset = -400; offset < 400; offset += 37.1) {
      const double world = AzimuthWorldFromGeographic(geo, offset);
      EXPECT_GE(world, 0.0);
      EXPECT_LT(world, 360.0);
      EXPECT_NEAR(AzimuthGeographicFromWorld(world, offset), geo, 1e-9);
    }
  }
}

TEST(WrapAzimuthDeg, KeepsEveryAngleInZeroTo360) {
  EXPECT_EQ(WrapAzimuthDeg(360.0), 0.0);
  EXPECT_EQ(WrapAzimuthDeg(-1e-15), 0.0);  // rounds to 360, which is 0
  EXPECT_NEAR(WrapAzimuthDeg(-90), 270, 1e-12);
  EXPECT_NEAR(WrapAzimuthDeg(725), 5, 1e-12);
}

TEST(AngleBetweenDeg, IsExactForTinyAndLargeAngles) {
  const Eigen::Vector3d a = SunInWorldFromAngles(40, 100);
  EXPECT_NEAR(AngleBetweenDeg(a, SunInWorldFromAngles(40.001, 100)), 0.001,
              1e-9);
  EXPECT_NEAR(AngleBetweenDeg(2 * a, -a), 180, 1e-9);
  EXPECT_NEAR(AngleBetweenDeg(SunInWorldFromAngles(90, 0),
                              SunInWorldFromAngles(90, 90)),
              90, 1e-9);
}

}  // namespace
}  // namespace sunlapse
