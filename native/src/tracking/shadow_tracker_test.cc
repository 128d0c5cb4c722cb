#include "sunlapse/tracking/shadow_tracker.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <thread>

#include "sunlapse/initial/initial_sun.h"
#include "synthetic.h"

namespace sunlapse {
namespace {

Eigen::Vector3d Sun(double zenith, double azimuth) {
  return SunInWorldFromAngles(zenith, azimuth);
}

// A textured ground (fixed in the world) under noise, like real paving.
testing::RenderOptions Textured(uint32_t seed) {
  testing::RenderOptions o;
  o.noise = 0.01;
  o.seed = seed;
  o.supersample = 3;
  o.albedo = [](int id, const Eigen::Vector3f& p) {
    if (id != 0) return 0.5;
    const double tiles = (static_cast<int>(std::floor(p.x() * 2)) +
                          static_cast<int>(std::floor(p.y() * 2))) %
                         2;
    return 0.3 + 0.06 * tiles +
           0.04 * std::sin(7.3 * p.x()) * std::cos(5.1 * p.y());
  };
  return o;
}

struct Fixture {
  Scene scene = testing::BoxAndPole().Build();
  Camera cam = testing::LookAt({3, -11, 8}, {0, 0, 0}, 320, 240);
  ShadowTrackerOptions Options() const {
    ShadowTrackerOptions o;
    o.ground_object_ids = {0};
    return o;
  }
};

// The Sun's path over a clip: zenith from 55 to 40 deg, azimuth 120 to 150.
Eigen::Vector3d PathAt(int f, int n) {
  const double t = static_cast<double>(f) / (n - 1);
  return Sun(55 - 15 * t, 120 + 30 * t);
}

// Frame f of a 40-frame clip along the path, over the textured ground.
cv::Mat PathFrame(const Fixture& fx, int f) {
  return testing::RenderLambertian(fx.scene, fx.cam, PathAt(f, 40),
                                   Textured(f + 1));
}

TEST(ShadowTracker, FollowsRotatingAndShorteningShadowsWithinHalfADegree) {
  Fixture fx;
  ShadowTracker tracker(fx.scene, fx.cam, fx.Options());
  const int n = 40;
  const TrackedFrame first = tracker.Initialize(
      testing::RenderLambertian(fx.scene, fx.cam, PathAt(0, n), Textured(1)),
      PathAt(0, n));
  ASSERT_TRUE(first.ok) << first.reason;
  EXPECT_TRUE(std::isfinite(first.shadow_end_px.x()));
  double worst = 0, sum = 0;
  for (int f = 1; f < n; ++f) {
    const cv::Mat img = testing::RenderLambertian(
        fx.scene, fx.cam, PathAt(f, n), Textured(f + 1));
    const TrackedFrame r = tracker.Track(img);
    ASSERT_TRUE(r.ok) << "frame " << f << ": " << r.reason;
    const double error = AngleBetweenDeg(r.sun_in_world, PathAt(f, n));
    worst = std::max(worst, error);
    sum += error;
    EXPECT_GT(r.confidence, 0.3);
  }
  std::printf("error over the clip: %.3f deg mean, %.3f worst\n", sum / (n - 1),
              worst);
  EXPECT_LT(worst, 0.5);
}

// The run decides between a doubtful tracker's Sun and a re-acquired one
// more than 2 deg from it by the contrast Initialize fits over the whole
// ground: the true Sun's shadows part lit from shaded ground best, so it must
// score highest against Suns 2-5 deg off either way. (At 1 deg a lower Sun
// can score a little higher: its smaller n.d raises the fitted slope.)
TEST(ShadowTracker, InitializeContrastPrefersTheTrueSun) {
  Fixture fx;
  const Eigen::Vector3d truth = PathAt(10, 40);
  const cv::Mat img =
      testing::RenderLambertian(fx.scene, fx.cam, truth, Textured(3));
  auto contrast = [&](const Eigen::Vector3d& sun) {
    ShadowTracker tracker(fx.scene, fx.cam, fx.Options());
    const TrackedFrame r = tracker.Initialize(img, sun);
    EXPECT_TRUE(r.ok) << r.reason;
    return r.contrast;
  };
  const double best = contrast(truth);
  for (double deg : {-5.0, -3.0, -2.0, 2.0, 3.0, 5.0}) {
    // Off in azimuth (about the vertical) and in zenith (about the horizontal).
    const Eigen::Vector3d axes[2] = {Eigen::Vector3d::UnitZ(),
                                     truth.cross(Eigen::Vector3d::UnitZ())};
    for (const Eigen::Vector3d& axis : axes) {
      const Eigen::Vector3d off =
          Eigen::AngleAxisd(deg * M_PI / 180, axis.normalized()) * truth;
      EXPECT_GT(best, contrast(off))
          << deg << " deg off about " << axis.transpose();
    }
  }
}

// A run re-initialises its tracker at every re-acquisition: a tracker
// initialised again tracks exactly as a fresh one (nothing piles up).
TEST(ShadowTracker, ReinitialisedTrackerTracksAsAFreshOne) {
  Fixture fx;
  const int n = 40;
  const cv::Mat f0 = PathFrame(fx, 0);
  const cv::Mat f1 = PathFrame(fx, 1);
  const cv::Mat f2 = PathFrame(fx, 2);
  ShadowTracker fresh(fx.scene, fx.cam, fx.Options()),
      again(fx.scene, fx.cam, fx.Options());
  ASSERT_TRUE(fresh.Initialize(f1, PathAt(1, n)).ok);
  ASSERT_TRUE(again.Initialize(f0, PathAt(0, n)).ok);
  again.Track(f1);
  ASSERT_TRUE(again.Initialize(f1, PathAt(1, n)).ok);
  const TrackedFrame a = fresh.Track(f2), b = again.Track(f2);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_EQ(a.rays, b.rays);
  EXPECT_EQ(a.band_pixels, b.band_pixels);
  EXPECT_EQ(a.sun_in_world, b.sun_in_world);
}

// The run maps the ground on another thread while its reference frames
// decode: a tracker so prepared tracks as one that maps on its first frame.
TEST(ShadowTracker, PreparedOnAnotherThreadTracksAsOneThatWasNot) {
  Fixture fx;
  const int n = 40;
  const cv::Mat f0 = PathFrame(fx, 0);
  const cv::Mat f1 = PathFrame(fx, 1);
  ShadowTracker plain(fx.scene, fx.cam, fx.Options()),
      prepared(fx.scene, fx.cam, fx.Options());
  std::thread beside([&] { prepared.Prepare(); });
  beside.join();
  prepared.Prepare();  // once is enough: a second call changes nothing
  const TrackedFrame a0 = plain.Initialize(f0, PathAt(0, n)),
                     b0 = prepared.Initialize(f0, PathAt(0, n));
  ASSERT_TRUE(a0.ok && b0.ok);
  EXPECT_EQ(a0.band_pixels, b0.band_pixels);
  EXPECT_EQ(a0.contrast, b0.contrast);
  const TrackedFrame a = plain.Track(f1), b = prepared.Track(f1);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_EQ(a.rays, b.rays);
  EXPECT_EQ(a.sun_in_world, b.sun_in_world);
}

// A moving camera's frame leaves the ground it does not see NaN: the first
// frame is fitted on the rest, and tracks as well; with most of the ground
// unseen it is refused with its reason.
TEST(ShadowTracker, GroundOutOfViewIsLeftOutOfTheFirstFrame) {
  Fixture fx;
  const int n = 40;
  const cv::Mat f0 = PathFrame(fx, 0);
  const cv::Mat f1 = PathFrame(fx, 1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat strip = f0.clone();
  strip(cv::Rect(0, 0, 40, f0.rows)).setTo(nan);  // the left edge unseen
  ShadowTracker tracker(fx.scene, fx.cam, fx.Options());
  const TrackedFrame first = tracker.Initialize(strip, PathAt(0, n));
  ASSERT_TRUE(first.ok) << first.reason;
  const TrackedFrame next = tracker.Track(f1);
  ASSERT_TRUE(next.ok) << next.reason;
  EXPECT_LT(AngleBetweenDeg(next.sun_in_world, PathAt(1, n)), 0.5);

  cv::Mat blind = f0.clone();
  blind(cv::Rect(0, 0, f0.cols * 9 / 10, f0.rows)).setTo(nan);
  ShadowTracker other(fx.scene, fx.cam, fx.Options());
  const TrackedFrame refused = other.Initialize(blind, PathAt(0, n));
  EXPECT_FALSE(refused.ok);
  EXPECT_EQ(refused.reason, "the ground is out of view on this frame");
}

// A clip with few, far-apart captures: the Sun jumps about 3 deg per frame,
// so the shadows' edges move many pixels between frames and the band must be
// found where the recorded caster points put them, not where they were.
TEST(ShadowTracker, FollowsASunThatJumpsSeveralDegreesPerFrame) {
  Fixture fx;
  ShadowTracker tracker(fx.scene, fx.cam, fx.Options());
  const int n = 12;
  ASSERT_TRUE(tracker
                  .Initialize(testing::RenderLambertian(
                                  fx.scene, fx.cam, PathAt(0, n), Textured(1)),
                              PathAt(0, n))
                  .ok);
  double worst = 0;
  for (int f = 1; f < n; ++f) {
    const TrackedFrame r = tracker.Track(testing::RenderLambertian(
        fx.scene, fx.cam, PathAt(f, n), Textured(f + 1)));
    ASSERT_TRUE(r.ok) << "frame " << f << ": " << r.reason;
    worst = std::max(worst, AngleBetweenDeg(r.sun_in_world, PathAt(f, n)));
  }
  std::printf("worst error with 3 deg steps: %.3f deg\n", worst);
  EXPECT_LT(worst, 0.5);
}

// A time-lapse that repeats each capture for several frames (the January
// sundial clip shows each for 13): the Sun stands still, so the tracker
// expects no motion, then jumps 3 deg at the next capture.
TEST(ShadowTracker, FollowsASunThatStandsStillThenJumps) {
  Fixture fx;
  ShadowTracker tracker(fx.scene, fx.cam, fx.Options());
  const int captures = 4, repeats = 5;
  auto sun = [&](int f) { return PathAt(f / repeats, 12); };
  ASSERT_TRUE(tracker
                  .Initialize(testing::RenderLambertian(fx.scene, fx.cam,
                                                        sun(0), Textured(1)),
                              sun(0))
                  .ok);
  double worst = 0;
  for (int f = 1; f < captures * repeats; ++f) {
    const TrackedFrame r = tracker.Track(
        testing::RenderLambertian(fx.scene, fx.cam, sun(f), Textured(f + 1)));
    ASSERT_TRUE(r.ok) << "frame " << f << ": " << r.reason;
    worst = std::max(worst, AngleBetweenDeg(r.sun_in_world, sun(f)));
  }
  std::printf("worst error with still Sun and 3 deg jumps: %.3f deg\n", worst);
  EXPECT_LT(worst, 0.5);
}

TEST(ShadowTracker, RecoversAfterBlackFramesAndAnOccluderCrossing) {
  Fixture fx;
  // The footage has a person-sized box walking across the pole's shadow.
  ShadowTracker tracker(fx.scene, fx.cam, fx.Options());
  const int n = 30;
  tracker.Initialize(
      testing::RenderLambertian(fx.scene, fx.cam, PathAt(0, n), Textured(1)),
      PathAt(0, n));
  int lost = 0;
  for (int f = 1; f < n; ++f) {
    cv::Mat img;
    if (f == 8 || f == 9) {
      img = cv::Mat(240, 320, CV_32F, 0.f);  // black frames
    } else if (f >= 15 && f <= 20) {
      testing::Mesh m = testing::BoxAndPole();
      const float x = 1.0f + 0.5f * (f - 15);
      m.Box({x, -4.5f, 0}, {x + 0.4f, -4.1f, 1.8f},
            3);  // a walker, not in the model
      img = testing::RenderLambertian(m.Build(), fx.cam, PathAt(f, n),
                                      Textured(f + 1));
    } else {
      img = testing::RenderLambertian(fx.scene, fx.cam, PathAt(f, n),
                                      Textured(f + 1));
    }
    const TrackedFrame r = tracker.Track(img);
    if (f == 8 || f == 9) {
      EXPECT_FALSE(r.ok);
      EXPECT_EQ(r.reason, "frame is black");
      ++lost;
      continue;
    }
    ASSERT_TRUE(r.ok) << "frame " << f << ": " << r.reason;
    EXPECT_LT(AngleBetweenDeg(r.sun_in_world, PathAt(f, n)), 1.0)
        << "frame " << f;
  }
  EXPECT_EQ(lost, 2);
}

TEST(ShadowTracker, UndecodableAndFlatFramesAreReportedNotGuessed) {
  Fixture fx;
  ShadowTracker tracker(fx.scene, fx.cam, fx.Options());
  tracker.Initialize(
      testing::RenderLambertian(fx.scene, fx.cam, Sun(40, 130), Textured(1)),
      Sun(40, 130));
  TrackedFrame r = tracker.Track(cv::Mat());
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.status, TrackedFrame::Status::kUnusableFrame);
  EXPECT_EQ(r.reason, "frame cannot be decoded");
  // Overcast: no direct Sun, the ground shows only its texture.
  testing::RenderOptions overcast = Textured(3);
  overcast.sun = 0.0;
  overcast.ambient = 0.6;
  r = tracker.Track(
      testing::RenderLambertian(fx.scene, fx.cam, Sun(40, 131), overcast));
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.status, TrackedFrame::Status::kNoContrast);
  EXPECT_NE(r.reason.find("shadow lost"), std::string::npos);
}

// A frame asked about a Sun whose shadows fall nowhere on the ground in view
// (a view of open ground away from the casters) is not a frame
// without sunlight: it cannot show the Sun's shadows, and says so by its
// status, which the whole-clip estimate reads (whole_clip.decide_sunlight).
TEST(ShadowTracker, ASunWhoseShadowsMissTheViewIsTold) {
  Fixture fx;
  // The camera looks south-east, away from the casters, whose shadows fall
  // to the north-west behind it.
  const Camera away = testing::LookAt({6, -6, 2}, {9, -9, 0}, 320, 240);
  ShadowTracker tracker(fx.scene, away, fx.Options());
  const Eigen::Vector3d sun = Sun(40, 130);
  const cv::Mat frame =
      testing::RenderLambertian(fx.scene, away, sun, Textured(1));
  const TrackedFrame first = tracker.Initialize(frame, sun);
  EXPECT_FALSE(first.ok);
  EXPECT_EQ(first.status, TrackedFrame::Status::kNoShadowInView);
  const TrackedFrame next = tracker.Track(frame, sun);
  EXPECT_FALSE(next.ok);
  EXPECT_EQ(next.status, TrackedFrame::Status::kNoShadowInView);
  // In view of the casters the same Sun is tracked.
  ShadowTracker near(fx.scene, fx.cam, fx.Options());
  const TrackedFrame seen = near.Initialize(
      testing::RenderLambertian(fx.scene, fx.cam, sun, Textured(1)), sun);
  EXPECT_TRUE(seen.ok) << seen.reason;
  EXPECT_EQ(seen.status, TrackedFrame::Status::kTracked);
}

// The misfit tells a model whose casters are not where the footage's are
// from the true one: the footage's box 0.3 m and 0.2 m off and 10% taller,
// its pole 0.2 m off both ways and 10% taller (a hand-made model's errors),
// tracked with the model as it is.
TEST(ShadowTracker, MisfitIsLowWithTheTrueModelAndHighWithAMisplacedCaster) {
  Fixture fx;
  testing::Mesh off;
  off.Ground(12, 0);
  off.Box({-1.2f, -0.8f, 0}, {0.8f, 1.4f, 1.76f}, 1);
  off.Box({2.7f, -2.4f, 0}, {2.85f, -2.25f, 3.3f}, 2);
  const Scene footage_scene = off.Build();
  const int n = 12;
  auto median_misfit = [&](const Scene& footage) {
    ShadowTracker tracker(fx.scene, fx.cam, fx.Options());
    tracker.Initialize(
        testing::RenderLambertian(footage, fx.cam, PathAt(0, n), Textured(1)),
        PathAt(0, n));
    std::vector<double> misfits;
    for (int f = 1; f < n; ++f) {
      const TrackedFrame r = tracker.Track(testing::RenderLambertian(
          footage, fx.cam, PathAt(f, n), Textured(f + 1)));
      if (r.ok) misfits.push_back(r.misfit);
    }
    EXPECT_GE(misfits.size(), static_cast<size_t>(n / 2));
    std::sort(misfits.begin(), misfits.end());
    return misfits.empty() ? -1.0 : misfits[misfits.size() / 2];
  };
  const double true_model = median_misfit(fx.scene);
  const double misplaced = median_misfit(footage_scene);
  std::printf("median misfit: true model %.3f, misplaced casters %.3f\n",
              true_model, misplaced);
  EXPECT_LT(true_model, 0.05);
  EXPECT_GT(misplaced, 0.1);
}

// A pole's shadow pins the Sun's elevation by its far end (the pole's top):
// seen whole, a degree higher or lower moves that end; with only its foot in
// view (a tight camera), any lower Sun lengthens it out of view alike.
TEST(ShadowTracker, ElevationIsPinnedOnlyWithTheShadowsFarEndInView) {
  const Scene scene = testing::PoleOnGround(12.f, 2.5f).Build();
  ShadowTrackerOptions o;
  o.ground_object_ids = {0};
  // The shadow runs 3 m toward -X, +Y (azimuth 135, zenith 50).
  auto pinned = [&](const Camera& cam, bool* tip_in_view) {
    ShadowTracker tracker(scene, cam, o);
    tracker.Initialize(
        testing::RenderLambertian(scene, cam, Sun(50, 133), Textured(1)),
        Sun(50, 133));
    const TrackedFrame r = tracker.Track(
        testing::RenderLambertian(scene, cam, Sun(50, 135), Textured(2)));
    EXPECT_TRUE(r.ok) << r.reason;
    *tip_in_view = std::isfinite(r.shadow_end_px.x());
    return r.elevation_pinned_deg;
  };
  bool wide_tip = false, tight_tip = true;
  const double wide =
      pinned(testing::LookAt({3, -7, 7}, {-1, 1, 0}, 320, 240), &wide_tip);
  const double tight =
      pinned(testing::LookAt({1.2, -2.5, 2.2}, {-0.4, 0.4, 0}, 320, 240, 70),
             &tight_tip);
  std::printf("elevation pinned within: whole shadow %g deg, foot only %g\n",
              wide, tight);
  ASSERT_TRUE(wide_tip);
  ASSERT_FALSE(tight_tip);
  EXPECT_LE(wide, 1.0);
  EXPECT_GT(tight, 8.0);
}

// A pole's shadow that runs into a wall ends, on the ground, at the wall's
// foot whatever the Sun's height: the ground leaves the height open. On the
// wall its far end (the pole's top) pins it, and the tracker fits such a
// frame again on every surface in view (surfaces_pin_deg).
TEST(ShadowTracker, AWallPinsTheHeightTheGroundLeavesOpen) {
  testing::Mesh mesh = testing::PoleOnGround(12.f, 2.5f);
  mesh.Box({-6, 2, 0}, {6, 2.3f, 4}, 2);
  const Scene scene = mesh.Build();
  const Camera cam = testing::LookAt({4, -6, 5}, {0, 1.5, 0.6}, 320, 240);
  // The shadow runs 3 m toward +Y: 2 m on the ground, then 0.8 m up the wall.
  const Eigen::Vector3d truth = Sun(50, 180);
  auto track = [&](double surfaces_pin_deg) {
    ShadowTrackerOptions o;
    o.ground_object_ids = {0};
    o.surfaces_pin_deg = surfaces_pin_deg;
    ShadowTracker tracker(scene, cam, o);
    tracker.Initialize(
        testing::RenderLambertian(scene, cam, truth, Textured(1)), truth);
    // Searched from a Sun 4 deg too high (a path's cell along the shadow).
    return tracker.Track(
        testing::RenderLambertian(scene, cam, truth, Textured(2)),
        Sun(46, 180));
  };
  const TrackedFrame ground = track(0.0);
  const TrackedFrame walls = track(ShadowTrackerOptions().surfaces_pin_deg);
  ASSERT_TRUE(ground.ok) << ground.reason;
  ASSERT_TRUE(walls.ok) << walls.reason;
  std::printf(
      "ground alone: %.2f deg off, pinned within %g; with the wall: %.2f deg "
      "off, pinned within %g\n",
      AngleBetweenDeg(ground.sun_in_world, truth), ground.elevation_pinned_deg,
      AngleBetweenDeg(walls.sun_in_world, truth), walls.elevation_pinned_deg);
  EXPECT_GT(ground.elevation_pinned_deg, 2.0);
  EXPECT_LE(walls.elevation_pinned_deg, 1.0);
  EXPECT_LT(AngleBetweenDeg(walls.sun_in_world, truth), 0.5);
}

// Initialised again (a run's re-acquisition), the tracker starts its walls'
// fit afresh too: its albedo is not the one of a frame before.
TEST(ShadowTracker, InitialisedAgainFitsTheWallsAsAFreshOne) {
  testing::Mesh mesh = testing::PoleOnGround(12.f, 2.5f);
  mesh.Box({-6, 2, 0}, {6, 2.3f, 4}, 2);
  const Scene scene = mesh.Build();
  const Camera cam = testing::LookAt({4, -6, 5}, {0, 1.5, 0.6}, 320, 240);
  ShadowTrackerOptions o;
  o.ground_object_ids = {0};
  const Eigen::Vector3d truth = Sun(50, 180), earlier = Sun(56, 165);
  const cv::Mat f0 = testing::RenderLambertian(scene, cam, truth, Textured(1));
  const cv::Mat f1 = testing::RenderLambertian(scene, cam, truth, Textured(2));
  ShadowTracker fresh(scene, cam, o), again(scene, cam, o);
  fresh.Initialize(f0, truth);
  const TrackedFrame want = fresh.Track(f1, Sun(46, 180));
  // The walls' fit first started on another frame, under another Sun.
  again.Initialize(testing::RenderLambertian(scene, cam, earlier, Textured(3)),
                   earlier);
  again.Track(testing::RenderLambertian(scene, cam, earlier, Textured(4)),
              Sun(52, 165));
  again.Initialize(f0, truth);
  const TrackedFrame got = again.Track(f1, Sun(46, 180));
  ASSERT_TRUE(want.ok && got.ok);
  EXPECT_EQ(got.sun_in_world, want.sun_in_world);
  EXPECT_EQ(got.elevation_pinned_deg, want.elevation_pinned_deg);
}

TEST(ShadowTracker, RejectsBadSetup) {
  Fixture fx;
  ShadowTrackerOptions o;  // no ground
  EXPECT_THROW(ShadowTracker(fx.scene, fx.cam, o), std::invalid_argument);
  o = fx.Options();
  o.surfaces_pin_deg = -1;
  EXPECT_THROW(ShadowTracker(fx.scene, fx.cam, o), std::invalid_argument);
  ShadowTracker tracker(fx.scene, fx.cam, fx.Options());
  EXPECT_THROW(tracker.Track(cv::Mat(240, 320, CV_32F, 0.5f)),
               std::invalid_argument);
  EXPECT_THROW(tracker.Initialize(cv::Mat(10, 10, CV_32F), Sun(40, 0)),
               std::invalid_argument);
}

}  // namespace
}  // namespace sunlapse
