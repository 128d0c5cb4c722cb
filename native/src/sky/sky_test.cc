#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <tbb/parallel_for.h>

#include "sunlapse/common/angles.h"
#include "sunlapse/sky/sky_evidence.h"
#include "sunlapse/sky/sun_path.h"
#include "synthetic.h"

namespace sunlapse {
namespace {

Eigen::Vector3d Sun(double zenith, double azimuth) {
  return SunInWorldFromAngles(zenith, azimuth);
}

// The Sun's path over a clip: zenith 55 -> 35 deg, azimuth 110 -> 160.
Eigen::Vector3d PathAt(int f, int n) {
  const double t = static_cast<double>(f) / (n - 1);
  return Sun(55 - 20 * t, 110 + 50 * t);
}

// The ground 30% brighter far from the camera than near it (view-dependent
// reflection, vignetting): no shadow, and it must not be taken for one.
cv::Mat WithGradient(cv::Mat f) {
  for (int y = 0; y < f.rows; ++y) {
    const float gain = 1.3f - 0.3f * y / f.rows;
    for (int x = 0; x < f.cols; ++x) f.at<float>(y, x) *= gain;
  }
  return f;
}

struct Clip {
  Scene scene = testing::BenchScene().Build();
  Camera cam = testing::LookAt({4, -12, 9}, {0, 0, 0}, 320, 240);
  std::vector<cv::Mat> frames;
  std::vector<Eigen::Vector3d> truth;
  explicit Clip(int n, bool gradient = true) {
    for (int f = 0; f < n; ++f) {
      truth.push_back(PathAt(f, n));
      cv::Mat img = testing::RenderLambertian(scene, cam, truth.back(),
                                              testing::TexturedGround(f + 1));
      frames.push_back(gradient ? WithGradient(img) : img);
    }
  }
};

std::vector<cv::Mat> Spread(const std::vector<cv::Mat>& frames, int k) {
  std::vector<cv::Mat> out;
  for (int i = 0; i < k; ++i)
    out.push_back(frames[i * (frames.size() - 1) / std::max(1, k - 1)]);
  return out;
}

// Each direction's cached neighbours are found in a zenith band around it:
// they must be exactly those a scan of the whole sky finds, nearest first.
TEST(SkyGrid, CachedNeighboursAreThoseOfAScanOfTheWholeSky) {
  for (const auto& [n, max_zenith] : std::vector<std::pair<int, double>>{
           {3000, 90.0}, {400, 60.0}, {16, 90.0}}) {
    const SkyGrid grid(n, max_zenith);
    const double cos_r = std::cos(grid.cached_radius_deg() * M_PI / 180.0);
    for (int i = 0; i < grid.size(); ++i) {
      std::vector<int> scanned;
      for (int j = 0; j < grid.size(); ++j) {
        if (grid.direction(i).dot(grid.direction(j)) >= cos_r)
          scanned.push_back(j);
      }
      std::vector<int> cached;
      float last = -1.f;
      for (const SkyGrid::Neighbour& nb : grid.Cached(i)) {
        cached.push_back(nb.index);
        EXPECT_GE(nb.angle_deg, last);
        last = nb.angle_deg;
      }
      std::sort(cached.begin(), cached.end());
      ASSERT_EQ(cached, scanned) << n << " directions, direction " << i;
    }
  }
}

// The lists are made on first use: asked for first by many tasks at once
// (each also copying the grid, which shares them), they are made once and
// are a lone caller's.
TEST(SkyGrid, NeighboursFirstAskedForByManyTasksAtOnceAreTheListsOfOneCaller) {
  const SkyGrid alone(1200, 88.0);
  const SkyGrid shared(1200, 88.0);
  std::vector<std::vector<int>> seen(shared.size());
  tbb::parallel_for(0, shared.size(), [&](int i) {
    const SkyGrid copy = shared;
    for (const SkyGrid::Neighbour& nb : copy.Cached(i))
      seen[i].push_back(nb.index);
  });
  for (int i = 0; i < alone.size(); ++i) {
    std::vector<int> expected;
    for (const SkyGrid::Neighbour& nb : alone.Cached(i))
      expected.push_back(nb.index);
    ASSERT_EQ(seen[i], expected) << "direction " << i;
    ASSERT_EQ(&shared.Cached(i), &SkyGrid(shared).Cached(i));
  }
}

TEST(SkyEvidence, BestDirectionOfEachFrameIsNearTheTrueSunDespiteAGradient) {
  Clip clip(12);
  SkyEvidence ev(clip.scene, clip.cam, SkyEvidenceOptions());
  ASSERT_GT(ev.num_samples(), 1000);
  ASSERT_EQ(ev.SetReference(Spread(clip.frames, 6)), 6);
  const double tolerance = 1.5 * ev.grid().spacing_deg();
  for (size_t f = 0; f < clip.frames.size(); ++f) {
    const FrameEvidence e = ev.AddFrame(clip.frames[f]);
    ASSERT_EQ(e.status, FrameEvidence::Status::kOk) << e.message;
    const double error =
        AngleBetweenDeg(ev.grid().direction(e.best_direction), clip.truth[f]);
    EXPECT_LT(error, tolerance) << "frame " << f;
    EXPECT_GT(e.best_explained, 0.1) << "frame " << f;
    EXPECT_GT(e.margin, 2.0) << "frame " << f;
  }
  std::printf("table: %d samples x %d directions in %.2f s\n", ev.num_samples(),
              ev.grid().size(), ev.build_seconds());
}

// The most samples one may ask for (65535), on a view the model fills: the
// stride's rounding would give more than the bands' 16-bit indices hold.
// The table takes fewer, and still finds the Sun.
TEST(SkyEvidence, TheLargestSampleCountAskedStaysWithinTheBandsIndices) {
  const Scene scene = testing::BenchScene().Build();
  const Camera cam = testing::LookAt({4, -12, 9}, {0, 0, 0}, 640, 480);
  SkyEvidenceOptions o;
  o.max_samples = 65535;
  o.num_directions = 400;
  SkyEvidence ev(scene, cam, o);
  EXPECT_LE(ev.num_samples(), 65536);
  EXPECT_GT(ev.num_samples(), 30000);
  std::vector<cv::Mat> frames;
  for (int f = 0; f < 3; ++f) {
    frames.push_back(testing::RenderLambertian(scene, cam, PathAt(5 * f, 11),
                                               testing::TexturedGround(f + 1)));
  }
  ASSERT_EQ(ev.SetReference(frames), 3);
  for (int f = 0; f < 3; ++f) {
    const FrameEvidence e = ev.AddFrame(frames[f]);
    ASSERT_EQ(e.status, FrameEvidence::Status::kOk) << e.message;
    EXPECT_LT(AngleBetweenDeg(ev.grid().direction(e.best_direction),
                              PathAt(5 * f, 11)),
              1.5 * ev.grid().spacing_deg())
        << "frame " << f;
  }
}

TEST(SkyEvidence, ShadowlessFrameWithAGradientExplainsNothing) {
  Clip clip(6);
  SkyEvidence ev(clip.scene, clip.cam, SkyEvidenceOptions());
  ev.SetReference(clip.frames);
  // An overcast frame: ambient light only, the same gradient.
  testing::RenderOptions o = testing::TexturedGround(99);
  o.sun = 0.0;
  o.ambient = 0.6;
  const cv::Mat overcast = WithGradient(
      testing::RenderLambertian(clip.scene, clip.cam, Sun(30, 100), o));
  const FrameEvidence e = ev.AddFrame(overcast);
  EXPECT_LT(e.best_explained, 0.1);
  // A frame of noise: nothing to explain either.
  cv::Mat noise(clip.cam.height(), clip.cam.width(), CV_32F);
  cv::randu(noise, 0.f, 1.f);
  EXPECT_LT(ev.AddFrame(noise).best_explained, 0.1);
}

TEST(SkyEvidence, BlackAndMissingFramesAreReportedNotScored) {
  Clip clip(4);
  SkyEvidence ev(clip.scene, clip.cam, SkyEvidenceOptions());
  ev.SetReference(clip.frames);
  EXPECT_EQ(ev.AddFrame(cv::Mat()).status, FrameEvidence::Status::kNoFrame);
  const cv::Mat black =
      cv::Mat::zeros(clip.cam.height(), clip.cam.width(), CV_32F);
  EXPECT_EQ(ev.AddFrame(black).status, FrameEvidence::Status::kUnusable);
  EXPECT_EQ(ev.num_frames(), 2);
  EXPECT_THROW(ev.AddFrame(cv::Mat::zeros(10, 10, CV_32F)),
               std::invalid_argument);
  SkyEvidenceOptions too_many;
  too_many.max_samples = 70000;  // the band's sample numbers are 16-bit
  EXPECT_THROW(too_many.Check(), std::invalid_argument);
}

// The path is the grid's: within reach of the tracker's refinement, which
// the whole-clip controller accepts up to 8 deg from the path.
constexpr double kPathToleranceDeg = 8.0;

double PathError(const SkyEvidence& ev, const SunPathResult& path,
                 const std::vector<Eigen::Vector3d>& truth, size_t t) {
  return AngleBetweenDeg(ev.grid().direction(path.direction[t]), truth[t]);
}

TEST(SunPath, BrokenFramesAreCarriedByTheirNeighbours) {
  const int n = 30;
  Clip clip(n);
  SkyEvidence ev(clip.scene, clip.cam, SkyEvidenceOptions());
  ev.SetReference(Spread(clip.frames, 8));
  cv::Mat noise(clip.cam.height(), clip.cam.width(), CV_32F);
  cv::randu(noise, 0.f, 1.f);
  std::vector<int> broken = {0, 1, 13, 14, 15, 22};
  for (int f = 0; f < n; ++f) {
    const bool bad = std::find(broken.begin(), broken.end(), f) != broken.end();
    ev.AddFrame(bad ? (f % 2 ? noise : cv::Mat()) : clip.frames[f]);
  }
  const SunPathResult path = SolveSunPath(ev, {}, {}, SunPathOptions());
  ASSERT_EQ(path.status, SunPathResult::Status::kSuccess) << path.message;
  const double tolerance = kPathToleranceDeg;
  for (int f = 0; f < n; ++f) {
    const bool bad = std::find(broken.begin(), broken.end(), f) != broken.end();
    EXPECT_LT(PathError(ev, path, clip.truth, f),
              bad ? 2 * tolerance : tolerance)
        << "frame " << f;
    if (bad) {
      EXPECT_FALSE(path.measured[f]) << "frame " << f;
    }
    EXPECT_FALSE(path.jump_before[f]) << "frame " << f;
  }
}

TEST(SunPath, ALoopedClipJumpsOnceAndStaysRightOnBothSides) {
  const int n = 20;
  Clip clip(n);
  SkyEvidence ev(clip.scene, clip.cam, SkyEvidenceOptions());
  ev.SetReference(Spread(clip.frames, 8));
  std::vector<Eigen::Vector3d> truth;
  for (int loop = 0; loop < 2; ++loop) {
    for (int f = 0; f < n; ++f)
      ev.AddFrame(clip.frames[f]), truth.push_back(clip.truth[f]);
  }
  const SunPathResult path = SolveSunPath(ev, {}, {}, SunPathOptions());
  ASSERT_EQ(path.status, SunPathResult::Status::kSuccess);
  // The grid's ~4 deg cells: a frame's evidence may peak a cell off the truth
  // along its shadows' ambiguous direction (refinement is the tracker's).
  const double tolerance = kPathToleranceDeg;
  int jumps = 0;
  for (int t = 0; t < 2 * n; ++t) {
    EXPECT_LT(PathError(ev, path, truth, t), tolerance) << "frame " << t;
    jumps += path.jump_before[t];
  }
  EXPECT_EQ(jumps, 1);
  EXPECT_TRUE(path.jump_before[n]);
}

// Longer than the solver's blocks of frames (without keep_forward_mb it
// keeps its forward costs only at block starts): jumps on a block's first
// frame and inside blocks are found alike, and every frame stays right;
// with the forward pass kept whole, the same path to the bit.
TEST(SunPath, ALongClipLoopedFiveTimesJumpsAtEveryLoop) {
  const int n = 32, loops = 5;
  Clip clip(n);
  SkyEvidence ev(clip.scene, clip.cam, SkyEvidenceOptions());
  ev.SetReference(Spread(clip.frames, 8));
  std::vector<Eigen::Vector3d> truth;
  for (int loop = 0; loop < loops; ++loop) {
    for (int f = 0; f < n; ++f)
      ev.AddFrame(clip.frames[f]), truth.push_back(clip.truth[f]);
  }
  SunPathOptions blocks;
  blocks.keep_forward_mb = 0;
  // Half the frames under a prior a few degrees off the truth, so that the
  // costs differ along the clip.
  std::vector<Eigen::Vector3d> prior(truth.size(), Eigen::Vector3d::Zero());
  for (size_t t = 0; t < truth.size(); t += 2)
    prior[t] = (truth[t] + Eigen::Vector3d(0.05, 0, 0)).normalized();
  for (const auto& with_prior : {std::vector<Eigen::Vector3d>(), prior}) {
    const SunPathResult path = SolveSunPath(ev, {}, {}, blocks, with_prior);
    const SunPathResult whole =
        SolveSunPath(ev, {}, {}, SunPathOptions(), with_prior);
    ASSERT_EQ(path.status, SunPathResult::Status::kSuccess);
    ASSERT_EQ(whole.status, SunPathResult::Status::kSuccess);
    EXPECT_EQ(whole.cost, path.cost);
    for (int t = 0; t < n * loops; ++t) {
      EXPECT_LT(PathError(ev, path, truth, t), kPathToleranceDeg)
          << "frame " << t;
      EXPECT_EQ(path.jump_before[t] != 0, t > 0 && t % n == 0) << "frame " << t;
      EXPECT_GT(path.path_margin[t], 0.f) << "frame " << t;
      EXPECT_EQ(whole.direction[t], path.direction[t]) << "frame " << t;
      EXPECT_EQ(whole.jump_before[t], path.jump_before[t]) << "frame " << t;
      EXPECT_EQ(whole.path_margin[t], path.path_margin[t]) << "frame " << t;
      EXPECT_EQ(whole.margin[t], path.margin[t]) << "frame " << t;
      EXPECT_EQ(whole.measured[t], path.measured[t]) << "frame " << t;
    }
  }
}

TEST(SunPath, KnownTimesBoundTheStepAndSegmentsRestart) {
  const int n = 16;
  Clip clip(n);
  SkyEvidence ev(clip.scene, clip.cam, SkyEvidenceOptions());
  ev.SetReference(Spread(clip.frames, 8));
  for (const cv::Mat& f : clip.frames) ev.AddFrame(f);
  std::vector<double> times;
  for (int f = 0; f < n; ++f) times.push_back(600.0 * f);  // 10 min apart
  std::vector<uint8_t> start(n, 0);
  start[8] = 1;
  const SunPathResult path = SolveSunPath(ev, times, start, SunPathOptions());
  ASSERT_EQ(path.status, SunPathResult::Status::kSuccess);
  EXPECT_TRUE(path.jump_before[8]);
  for (int t = 0; t < n; ++t) {
    EXPECT_LT(PathError(ev, path, clip.truth, t), kPathToleranceDeg)
        << "frame " << t;
  }
  EXPECT_THROW(SolveSunPath(ev, {1.0}, {}, SunPathOptions()),
               std::invalid_argument);
}

// A run of frames whose evidence points 15 deg from the Sun (as the sky
// grid's ridge along a long thin shadow does on low-Sun frames): without a
// prior the path follows them; with the Sun's circle as the prior it stays
// with the Sun, and the frames' own margins still say their evidence
// disagrees (a prior does not make a frame measured).
// Frames found without direct sunlight: their evidence is left out and the
// path carries them, as frames without evidence.
TEST(SunPath, IgnoredFramesAreCarriedNotFollowed) {
  const int n = 16;
  Clip clip(n);
  SkyEvidence ev(clip.scene, clip.cam, SkyEvidenceOptions());
  ev.SetReference(Spread(clip.frames, 8));
  const std::vector<int> misled = {5, 6, 7, 8};
  std::vector<uint8_t> ignored(n, 0);
  for (int f = 0; f < n; ++f) {
    const bool bad = std::find(misled.begin(), misled.end(), f) != misled.end();
    double zenith, azimuth;
    AnglesFromSunInWorld(clip.truth[f], &zenith, &azimuth);
    ev.AddFrame(bad ? testing::RenderLambertian(clip.scene, clip.cam,
                                                Sun(zenith + 15.0, azimuth),
                                                testing::TexturedGround(f + 1))
                    : clip.frames[f]);
    ignored[f] = bad;
  }
  const SunPathResult path =
      SolveSunPath(ev, {}, {}, SunPathOptions(), {}, ignored);
  ASSERT_EQ(path.status, SunPathResult::Status::kSuccess) << path.message;
  for (int f = 0; f < n; ++f) {
    EXPECT_LT(PathError(ev, path, clip.truth, f), kPathToleranceDeg)
        << "frame " << f;
    EXPECT_EQ(path.measured[f], !ignored[f]) << "frame " << f;
  }
  EXPECT_THROW(SolveSunPath(ev, {}, {}, SunPathOptions(), {}, {1, 0}),
               std::invalid_argument);
  const SunPathResult none = SolveSunPath(ev, {}, {}, SunPathOptions(), {},
                                          std::vector<uint8_t>(n, 1));
  EXPECT_EQ(none.status, SunPathResult::Status::kNoEvidence);
}

TEST(SunPath, APriorHoldsThePathAgainstMisleadingFrames) {
  const int n = 16;
  Clip clip(n);
  SkyEvidence ev(clip.scene, clip.cam, SkyEvidenceOptions());
  ev.SetReference(Spread(clip.frames, 8));
  const std::vector<int> misled = {5, 6, 7, 8};
  for (int f = 0; f < n; ++f) {
    const bool bad = std::find(misled.begin(), misled.end(), f) != misled.end();
    if (!bad) {
      ev.AddFrame(clip.frames[f]);
      continue;
    }
    double zenith, azimuth;
    AnglesFromSunInWorld(clip.truth[f], &zenith, &azimuth);
    ev.AddFrame(testing::RenderLambertian(clip.scene, clip.cam,
                                          Sun(zenith + 15.0, azimuth),
                                          testing::TexturedGround(f + 1)));
  }
  const SunPathResult plain = SolveSunPath(ev, {}, {}, SunPathOptions());
  const SunPathResult held =
      SolveSunPath(ev, {}, {}, SunPathOptions(), clip.truth);
  ASSERT_EQ(plain.status, SunPathResult::Status::kSuccess);
  ASSERT_EQ(held.status, SunPathResult::Status::kSuccess);
  for (int f : misled) {
    EXPECT_GT(PathError(ev, plain, clip.truth, f), 10.0) << "frame " << f;
    EXPECT_LT(PathError(ev, held, clip.truth, f), 1.5 * ev.grid().spacing_deg())
        << "frame " << f;
    EXPECT_FALSE(held.measured[f]) << "frame " << f;
  }
  for (int f = 0; f < n; ++f) {
    EXPECT_LT(PathError(ev, held, clip.truth, f), kPathToleranceDeg)
        << "frame " << f;
  }
  // A prior that costs nothing changes nothing.
  SunPathOptions free;
  free.prior_max_cost = 0.0;
  const SunPathResult same = SolveSunPath(ev, {}, {}, free, clip.truth);
  EXPECT_EQ(same.direction, plain.direction);
  EXPECT_THROW(SolveSunPath(ev, {}, {}, SunPathOptions(), {clip.truth[0]}),
               std::invalid_argument);
  SunPathOptions bad;
  bad.prior_weight = -1.0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace sunlapse
