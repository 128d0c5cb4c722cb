#include "sunlapse/sky/sun_circle.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "sunlapse/common/angles.h"

namespace sunlapse {
namespace {

// The Sun at hour angle H (deg, positive in the afternoon) for a latitude and
// declination, in a scene whose +Y is turned by north_offset from true north:
// the textbook horizontal coordinates, independent of the fit's basis.
Eigen::Vector3d SunAt(double latitude, double declination, double hour,
                      double north_offset) {
  const double phi = latitude * kRadPerDeg, dec = declination * kRadPerDeg;
  const double h = hour * kRadPerDeg;
  const double up = std::sin(phi) * std::sin(dec) +
                    std::cos(phi) * std::cos(dec) * std::cos(h);
  const double east = -std::cos(dec) * std::sin(h);
  const double north = std::cos(phi) * std::sin(dec) -
                       std::sin(phi) * std::cos(dec) * std::cos(h);
  double zenith = 0.0, azimuth_geographic = 0.0;
  AnglesFromSunInWorld({east, north, up}, &zenith, &azimuth_geographic);
  return SunInWorldFromAngles(
      zenith, AzimuthWorldFromGeographic(azimuth_geographic, north_offset));
}

struct Day {
  std::vector<double> times;  // seconds
  std::vector<double> hours;  // hour angles, deg
  std::vector<Eigen::Vector3d> suns;
};

// A morning to afternoon: 9:00 to 15:00 solar time, one frame a minute.
Day MakeDay(double latitude, double declination, double north_offset,
            int frames = 60) {
  Day d;
  for (int i = 0; i < frames; ++i) {
    const double hour = -45.0 + 90.0 * i / (frames - 1);
    d.hours.push_back(hour);
    d.times.push_back(40000.0 + hour / 15.0 * 3600.0);
    d.suns.push_back(SunAt(latitude, declination, hour, north_offset));
  }
  return d;
}

TEST(SunCircle, RecoversLatitudeDeclinationNorthAndHourFromTimedSuns) {
  const Day d = MakeDay(40.0, 15.0, 20.0);
  const SunCircleFit fit = FitSunCircle(d.times, d.suns, {}, {});
  ASSERT_EQ(fit.status, SunCircleFit::Status::kSuccess) << fit.message;
  EXPECT_NEAR(fit.latitude_deg, 40.0, 1e-6);
  EXPECT_NEAR(fit.declination_deg, 15.0, 1e-6);
  EXPECT_NEAR(fit.north_offset_deg, 20.0, 1e-6);
  EXPECT_NEAR(fit.rate_deg, 15.0 / 3600.0, 1e-12);
  EXPECT_LT(fit.residual_deg, 1e-6);
  for (size_t i = 0; i < d.suns.size(); ++i) {
    EXPECT_NEAR(fit.hour_angle_deg[i], d.hours[i], 1e-6);
    EXPECT_LT(AngleBetweenDeg(fit.sun_in_world[i], d.suns[i]), 1e-6);
  }
}

TEST(SunCircle, FitsTheRateWhenTimesAreFrameNumbers) {
  Day d = MakeDay(-33.0, -20.0, 250.0, 30);
  std::vector<double> frames;
  for (size_t i = 0; i < d.suns.size(); ++i) frames.push_back(i + 1.0);
  SunCircleOptions options;
  options.times_are_seconds = false;
  const SunCircleFit fit = FitSunCircle(frames, d.suns, {}, options);
  ASSERT_EQ(fit.status, SunCircleFit::Status::kSuccess) << fit.message;
  EXPECT_NEAR(fit.latitude_deg, -33.0, 1e-5);
  EXPECT_NEAR(fit.declination_deg, -20.0, 1e-5);
  EXPECT_NEAR(fit.north_offset_deg, 250.0, 1e-5);
  EXPECT_NEAR(fit.rate_deg, 90.0 / 29.0, 1e-6);  // deg a frame
}

TEST(SunCircle, PredictsFramesWithoutASunAndIgnoresZeroWeights) {
  Day d = MakeDay(50.0, 5.0, 0.0, 40);
  const Eigen::Vector3d truth = d.suns[7];
  d.suns[7] = Eigen::Vector3d::Constant(std::nan(""));
  std::vector<double> weights(d.suns.size(), 1.0);
  d.suns[9] = SunInWorldFromAngles(80.0, 10.0);  // absurd, but weighs nothing
  const Eigen::Vector3d truth9 = SunAt(50.0, 5.0, d.hours[9], 0.0);
  weights[9] = 0.0;
  const SunCircleFit fit = FitSunCircle(d.times, d.suns, weights, {});
  ASSERT_EQ(fit.status, SunCircleFit::Status::kSuccess);
  EXPECT_LT(AngleBetweenDeg(fit.sun_in_world[7], truth), 1e-6);
  EXPECT_LT(AngleBetweenDeg(fit.sun_in_world[9], truth9), 1e-6);
}

TEST(SunCircle, ThePoleAtTheZenithStillFits) {
  // At the pole the basis jumps and the Jacobian is taken numerically.
  const Day d = MakeDay(90.0 - 1e-12, 10.0, 0.0, 24);
  const SunCircleFit fit = FitSunCircle(d.times, d.suns, {}, {});
  ASSERT_EQ(fit.status, SunCircleFit::Status::kSuccess);
  EXPECT_NEAR(fit.declination_deg, 10.0, 1e-4);
  EXPECT_FALSE(fit.message.empty());  // latitude from the path: a caveat
  for (size_t i = 0; i < d.suns.size(); ++i)
    EXPECT_LT(AngleBetweenDeg(fit.sun_in_world[i], d.suns[i]), 1e-4);
}

TEST(SunCircle, StoppingOnceSettledGivesTheSameCircle) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.004);
  Day d = MakeDay(45.0, 20.0, 30.0, 80);
  for (auto& s : d.suns)
    s += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const SunCircleFit early = FitSunCircle(d.times, d.suns, {}, {});
  SunCircleOptions every;
  every.settled_step_rad = 0.0;
  const SunCircleFit full = FitSunCircle(d.times, d.suns, {}, every);
  ASSERT_EQ(early.status, SunCircleFit::Status::kSuccess);
  for (size_t i = 0; i < d.suns.size(); ++i)
    EXPECT_LT(AngleBetweenDeg(early.sun_in_world[i], full.sun_in_world[i]),
              1e-7);
}

TEST(SunCircle, SaysWhyItCannotFit) {
  const Day d = MakeDay(40.0, 15.0, 20.0, 6);
  const std::vector<double> three(d.times.begin(), d.times.begin() + 3);
  const std::vector<Eigen::Vector3d> three_suns(d.suns.begin(),
                                                d.suns.begin() + 3);
  EXPECT_EQ(FitSunCircle(three, three_suns, {}, {}).status,
            SunCircleFit::Status::kTooFewSuns);
  const std::vector<double> same(6, 5.0);
  EXPECT_EQ(FitSunCircle(same, d.suns, {}, {}).status,
            SunCircleFit::Status::kSameTimes);
  EXPECT_THROW(FitSunCircle(d.times, three_suns, {}, {}),
               std::invalid_argument);
  EXPECT_THROW(FitSunCircle(d.times, d.suns, {1.0}, {}), std::invalid_argument);
  SunCircleOptions bad;
  bad.iterations = 0;
  EXPECT_THROW(FitSunCircle(d.times, d.suns, {}, bad), std::invalid_argument);
  TrimmedCircleOptions bad_trim;
  bad_trim.min_frames = 3;
  EXPECT_THROW(bad_trim.Check(), std::invalid_argument);
}

// A third of the Suns, the low-Sun end, 3 deg lower than the path (the
// sky's evidence along a long thin shadow), the rest with 0.1 deg of noise.
Day StuckLowEnd(std::vector<Eigen::Vector3d>* truth) {
  Day d = MakeDay(40.0, 15.0, 20.0, 90);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.1);
  for (size_t i = 0; i < d.suns.size(); ++i) {
    truth->push_back(d.suns[i]);
    double zenith = 0.0, azimuth = 0.0;
    AnglesFromSunInWorld(d.suns[i], &zenith, &azimuth);
    if (i < d.suns.size() / 3) zenith += 3.0;
    d.suns[i] = SunInWorldFromAngles(zenith + noise(rng), azimuth + noise(rng));
  }
  return d;
}

TEST(TrimmedSunCircle, ARunOfWrongSunsDoesNotBendIt) {
  std::vector<Eigen::Vector3d> truth;
  const Day d = StuckLowEnd(&truth);
  const SunCircleFit plain = FitSunCircle(d.times, d.suns, {}, {});
  const SunCircleFit trimmed =
      FitTrimmedSunCircle(d.times, d.suns, {}, 0.5, {}, {});
  ASSERT_EQ(trimmed.status, SunCircleFit::Status::kSuccess) << trimmed.message;
  double plain_worst = 0.0, trimmed_worst = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    plain_worst =
        std::max(plain_worst, AngleBetweenDeg(plain.sun_in_world[i], truth[i]));
    trimmed_worst = std::max(
        trimmed_worst, AngleBetweenDeg(trimmed.sun_in_world[i], truth[i]));
  }
  EXPECT_GT(plain_worst, 0.5);
  EXPECT_LT(trimmed_worst, 0.2);
  // The stuck third is out, the rest in.
  for (int i : trimmed.inliers) EXPECT_GE(i, 30);
  EXPECT_GE(trimmed.inliers.size(), 55u);
  ASSERT_EQ(trimmed.off_deg.size(), truth.size());
  EXPECT_GT(trimmed.off_deg[0], 2.0);
  EXPECT_LT(trimmed.residual_deg, 0.2);
}

TEST(TrimmedSunCircle, SpreadsItsRoundsOverALongSegmentAndNeedsEnoughSuns) {
  std::vector<Eigen::Vector3d> truth;
  const Day d = StuckLowEnd(&truth);
  TrimmedCircleOptions few;
  few.max_fit_frames = 20;  // the rounds see 20 of the 90 Suns
  const SunCircleFit fit =
      FitTrimmedSunCircle(d.times, d.suns, {}, 0.5, {}, few);
  ASSERT_EQ(fit.status, SunCircleFit::Status::kSuccess);
  for (size_t i = 0; i < truth.size(); ++i)
    EXPECT_LT(AngleBetweenDeg(fit.sun_in_world[i], truth[i]), 0.3);
  std::vector<Eigen::Vector3d> seven(d.suns.size(),
                                     Eigen::Vector3d::Constant(std::nan("")));
  for (int i = 0; i < 7; ++i) seven[i * 10] = d.suns[i * 10];
  const SunCircleFit none =
      FitTrimmedSunCircle(d.times, seven, {}, 0.5, {}, {});
  EXPECT_EQ(none.status, SunCircleFit::Status::kTooFewSuns);
  EXPECT_NE(none.message.find("8"), std::string::npos);
}

}  // namespace
}  // namespace sunlapse
