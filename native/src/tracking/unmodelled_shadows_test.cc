#include "sunlapse/tracking/unmodelled_shadows.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "synthetic.h"

namespace sunlapse {
namespace {

Eigen::Vector3d Sun(double zenith, double azimuth) {
  return SunInWorldFromAngles(zenith, azimuth);
}

testing::RenderOptions Paving(uint32_t seed) {
  testing::RenderOptions o;
  o.seed = seed;
  o.supersample = 2;
  o.albedo = [](int id, const Eigen::Vector3f& p) {
    if (id != 0) return 0.5;
    const int tiles = (static_cast<int>(std::floor(p.x() * 2)) +
                       static_cast<int>(std::floor(p.y() * 2))) %
                      2;
    return 0.3 + 0.05 * std::abs(tiles) +
           0.04 * std::sin(7.3 * p.x()) * std::cos(5.1 * p.y());
  };
  return o;
}

// The model is BoxAndPole; the footage also has a bin (id 5) the artist did
// not model.
struct Fixture {
  testing::Mesh model_mesh = testing::BoxAndPole();
  Scene model = model_mesh.Build();
  Scene footage = [] {
    testing::Mesh m = testing::BoxAndPole();
    m.Box({3.0f, 0.5f, 0}, {3.7f, 1.2f, 1.5f}, 5);
    return m.Build();
  }();
  Camera cam = testing::LookAt({3, -11, 8}, {0, 0, 0}, 320, 240);
  Eigen::Vector3d sun = Sun(50, 250);  // shadows fall east, across the view
  cv::Mat1b ground, model_shadow,
      truth;  // truth: the bin's shadow on the ground

  // Per-pixel masks by ray casting: ground seen in the model, shadow under
  // `sun` in the model and in the footage.
  Fixture() {
    const int W = cam.width(), H = cam.height();
    std::vector<Eigen::Vector2d> px;
    for (int y = 0; y < H; ++y) {
      for (int x = 0; x < W; ++x) px.emplace_back(x, y);
    }
    const Hits in_model = model.IntersectPixels(cam, px);
    const Hits in_footage = footage.IntersectPixels(cam, px);
    ground = cv::Mat1b(H, W, uint8_t(0));
    model_shadow = ground.clone();
    truth = ground.clone();
    std::vector<float> origins;
    std::vector<int> index;
    for (int i = 0; i < W * H; ++i) {
      if (!in_model.hit(i) || in_model.object_id[i] != 0) continue;
      ground(i / W, i % W) = 255;
      if (in_footage.object_id[i] != 0) continue;  // the bin stands there
      const Eigen::Vector3f p =
          in_model.point(i) + 1e-3f * Eigen::Vector3f::UnitZ();
      origins.insert(origins.end(), {p.x(), p.y(), p.z()});
      index.push_back(i);
    }
    std::vector<uint8_t> occ_model(index.size()), occ_footage(index.size());
    const Eigen::Vector3f d = sun.cast<float>();
    const float inf = std::numeric_limits<float>::infinity();
    model.OccludedToward(index.size(), origins.data(), d, 0.f, inf,
                         occ_model.data());
    footage.OccludedToward(index.size(), origins.data(), d, 0.f, inf,
                           occ_footage.data());
    for (size_t k = 0; k < index.size(); ++k) {
      const int y = index[k] / W, x = index[k] % W;
      if (occ_model[k]) model_shadow(y, x) = 255;
      if (occ_footage[k] && !occ_model[k]) truth(y, x) = 255;
    }
  }

  // The clip's background: the median of frames whose Sun went round.
  cv::Mat Background(const Scene& scene) const {
    std::vector<cv::Mat> frames;
    for (int k = 0; k < 7; ++k) {
      frames.push_back(testing::RenderLambertian(
          scene, cam, Sun(45, 40 + 45 * k), Paving(20 + k)));
    }
    cv::Mat out(frames[0].size(), CV_32F);
    std::vector<float> v(frames.size());
    for (int y = 0; y < out.rows; ++y) {
      for (int x = 0; x < out.cols; ++x) {
        for (size_t k = 0; k < frames.size(); ++k)
          v[k] = frames[k].at<float>(y, x);
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        out.at<float>(y, x) = v[v.size() / 2];
      }
    }
    return out;
  }
};

double Share(const cv::Mat1b& a, const cv::Mat1b& b) {  // |a & b| / |a|
  return static_cast<double>(cv::countNonZero(a & b)) /
         std::max(1, cv::countNonZero(a));
}

TEST(UnmodelledShadows, FindsTheShadowOfACasterMissingFromTheModel) {
  Fixture fx;
  ASSERT_GT(cv::countNonZero(fx.truth), 100);
  const cv::Mat frame =
      testing::RenderLambertian(fx.footage, fx.cam, fx.sun, Paving(1));
  const UnmodelledShadows r = DetectUnmodelledShadows(
      frame, fx.Background(fx.footage), fx.ground, fx.model_shadow);
  ASSERT_FALSE(r.regions.empty());
  const double precision = Share(r.mask, fx.truth),
               recall = Share(fx.truth, r.mask);
  std::printf("bin's shadow: precision %.3f, recall %.3f, %zu region(s)\n",
              precision, recall, r.regions.size());
  EXPECT_GT(precision, 0.85);
  EXPECT_GT(recall, 0.8);
  EXPECT_EQ(r.regions.size(), 1u);
  EXPECT_LT(r.regions[0].darkening, 0.5);
  EXPECT_GT(r.regions[0].edge_contrast, 2.5);
  EXPECT_FALSE(r.regions[0].touches_model);  // the bin stands apart
}

TEST(UnmodelledShadows, FindsItInOneFrameWithoutABackground) {
  // A short clip whose shadows hardly moved has no shadow-free background:
  // the frame's own lit ground around the shadow is the reference.
  Fixture fx;
  const cv::Mat frame =
      testing::RenderLambertian(fx.footage, fx.cam, fx.sun, Paving(4));
  const UnmodelledShadows r =
      DetectUnmodelledShadows(frame, cv::Mat(), fx.ground, fx.model_shadow);
  ASSERT_FALSE(r.regions.empty());
  const double precision = Share(r.mask, fx.truth),
               recall = Share(fx.truth, r.mask);
  std::printf(
      "bin's shadow, one frame: precision %.3f, recall %.3f, %zu region(s)\n",
      precision, recall, r.regions.size());
  EXPECT_GT(precision, 0.85);
  EXPECT_GT(recall, 0.8);
}

TEST(UnmodelledShadows, ReportsNothingWhenTheModelExplainsEveryShadow) {
  Fixture fx;
  const cv::Mat frame =
      testing::RenderLambertian(fx.model, fx.cam, fx.sun, Paving(2));
  const UnmodelledShadows r = DetectUnmodelledShadows(
      frame, fx.Background(fx.model), fx.ground, fx.model_shadow);
  EXPECT_TRUE(r.regions.empty())
      << r.regions.size() << " region(s), the first of " << r.regions[0].area_px
      << " px";
  const UnmodelledShadows alone =
      DetectUnmodelledShadows(frame, cv::Mat(), fx.ground, fx.model_shadow);
  EXPECT_TRUE(alone.regions.empty())
      << alone.regions.size() << " region(s) in the frame alone";
  // Without the model's shadow to explain it, the box's shadow is found.
  const UnmodelledShadows all =
      DetectUnmodelledShadows(frame, fx.Background(fx.model), fx.ground,
                              cv::Mat1b(fx.ground.size(), uint8_t(0)));
  EXPECT_FALSE(all.regions.empty());
  EXPECT_GT(Share(fx.model_shadow, all.mask), 0.7);
  // Told of a Sun a little off, the true shadow's uncovered part is found
  // but marked as bordering the model's (misplaced) shadow.
  cv::Mat1b shifted;
  cv::warpAffine(fx.model_shadow, shifted, cv::Matx23d(1, 0, 12, 0, 1, 0),
                 fx.model_shadow.size(), cv::INTER_NEAREST);
  const UnmodelledShadows off = DetectUnmodelledShadows(
      frame, fx.Background(fx.model), fx.ground, shifted & fx.ground);
  ASSERT_FALSE(off.regions.empty());
  for (const UnmodelledShadow& u : off.regions)
    EXPECT_TRUE(u.touches_model) << u.area_px;
}

TEST(UnmodelledShadows, ASoftDarkeningIsNotAHardShadow) {
  // A cloud's shadow: the ground dims by half, smoothly, over a wide patch.
  Fixture fx;
  cv::Mat frame =
      testing::RenderLambertian(fx.model, fx.cam, fx.sun, Paving(3));
  for (int y = 0; y < frame.rows; ++y) {
    for (int x = 0; x < frame.cols; ++x) {
      const double r2 =
          (std::pow(x - 200.0, 2) + std::pow(y - 150.0, 2)) / (2 * 35.0 * 35.0);
      frame.at<float>(y, x) *= static_cast<float>(1.0 - 0.6 * std::exp(-r2));
    }
  }
  const UnmodelledShadows r = DetectUnmodelledShadows(
      frame, fx.Background(fx.model), fx.ground, fx.model_shadow);
  EXPECT_TRUE(r.regions.empty()) << r.regions.size() << " region(s)";
}

TEST(UnmodelledShadows, RejectsMismatchedInputs) {
  const cv::Mat f(10, 10, CV_32F, 0.5f),
      b3(10, 10, CV_32FC3, cv::Scalar::all(0.5));
  const cv::Mat1b m(10, 10, uint8_t(255)), small(5, 5, uint8_t(255));
  EXPECT_THROW(DetectUnmodelledShadows(f, b3, m, m), std::invalid_argument);
  EXPECT_THROW(DetectUnmodelledShadows(f, f, small, m), std::invalid_argument);
  EXPECT_THROW(DetectUnmodelledShadows(cv::Mat(), f, m, m),
               std::invalid_argument);
  UnmodelledShadowOptions bad;
  bad.dark_ratio = 1.5;
  EXPECT_THROW(DetectUnmodelledShadows(f, f, m, m, bad), std::invalid_argument);
}

}  // namespace
}  // namespace sunlapse
