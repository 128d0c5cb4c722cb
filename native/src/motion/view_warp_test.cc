#include "sunlapse/motion/view_warp.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "../testing/synthetic.h"

namespace sunlapse {
namespace {

using testing::LookAt;
using testing::RenderLambertian;
using testing::RenderOptions;

constexpr int kW = 320, kH = 180;

// Ground dark, everything standing on it bright, no Sun and no noise: a
// frame's value at a pixel says which object it shows.
RenderOptions Flat() {
  RenderOptions o;
  o.ambient = 1.0;
  o.sun = 0.0;
  o.noise = 0.0;
  o.albedo = [](int id, const Eigen::Vector3f&) { return id == 0 ? 0.2 : 0.9; };
  return o;
}

const Eigen::Vector3d kDown(0, 0, 1);  // "Sun" unused (sun = 0)

TEST(ViewWarp, TheSameCameraGivesTheFrameBackWhereTheModelIsSeen) {
  const Scene scene = testing::BoxAndPole().Build();
  const Camera cam = LookAt({3, -11, 8}, {0, 0, 0}, kW, kH);
  RenderOptions o = testing::TexturedGround(3);
  const cv::Mat frame = RenderLambertian(scene, cam, {0.3, -0.4, 0.8}, o);
  const ViewWarp warp(scene, cam);
  cv::Mat out;
  const ViewWarpResult r = warp.Warp(frame, cam, &out);
  ASSERT_EQ(r.status, ViewWarpResult::Status::kOk) << r.message;
  EXPECT_GT(r.seen_share, 0.99);
  double worst = 0;
  int finite = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float v = out.at<float>(y, x);
      if (std::isnan(v)) continue;
      ++finite;
      worst = std::max(worst, double(std::abs(v - frame.at<float>(y, x))));
    }
  EXPECT_GT(finite, warp.model_pixels() * 0.98);
  EXPECT_LT(worst, 1e-3);
}

TEST(ViewWarp,
     AMovedCameraIsResampledIntoTheReferenceViewAndHiddenPointsAreLeftOut) {
  const Scene scene = testing::BoxAndPole().Build();
  const Camera reference = LookAt({3, -11, 8}, {0, 0, 0}, kW, kH);
  // A slide of 4 m to the side and a pan: the box hides other ground.
  const Camera moved = LookAt({-1, -11, 6}, {-1, 1, 0}, kW, kH);
  const cv::Mat frame = RenderLambertian(scene, moved, kDown, Flat());
  const ViewWarp warp(scene, reference);
  cv::Mat out;
  const ViewWarpResult r = warp.Warp(frame, moved, &out);
  ASSERT_EQ(r.status, ViewWarpResult::Status::kOk) << r.message;
  EXPECT_GT(r.seen_share, 0.3);
  EXPECT_LT(r.seen_share, 0.99);
  // What the reference view sees where: ground (0) or not.
  std::vector<Eigen::Vector2d> pixels;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) pixels.emplace_back(x, y);
  const Hits hits = scene.IntersectPixels(reference, pixels);
  int ground_seen = 0, wrong = 0, hidden_ground = 0;
  for (int i = 0; i < kW * kH; ++i) {
    const float v = out.at<float>(i / kW, i % kW);
    if (!hits.hit(i)) {
      EXPECT_TRUE(std::isnan(v)) << "no model at pixel " << i;
      continue;
    }
    if (hits.object_id[i] != 0) continue;
    if (std::isnan(v)) {
      ++hidden_ground;
      continue;
    }
    ++ground_seen;
    // Bilinear mixes a pixel at an object's outline: only clear misses count
    // (a ground point showing the box in front of it).
    wrong += v > 0.5f;
  }
  EXPECT_GT(ground_seen, 5000);
  EXPECT_GT(hidden_ground, 50);  // the box and the pole hide some ground
  EXPECT_LT(wrong, ground_seen / 200) << wrong << " of " << ground_seen;
}

TEST(ViewWarp, TheCoarseDepthGridSeesWhatARayPerPointSees) {
  const Scene scene = testing::BoxAndPole().Build();
  const Camera reference = LookAt({3, -11, 8}, {0, 0, 0}, kW, kH);
  const Camera moved = LookAt({-1, -11, 6}, {-1, 1, 0}, kW, kH);
  const cv::Mat frame = RenderLambertian(scene, moved, kDown, Flat());
  ViewWarpOptions exact;
  exact.depth_step = 1;
  cv::Mat coarse_out, exact_out;
  const ViewWarpResult coarse =
      ViewWarp(scene, reference).Warp(frame, moved, &coarse_out);
  const ViewWarpResult every =
      ViewWarp(scene, reference, exact).Warp(frame, moved, &exact_out);
  ASSERT_EQ(coarse.status, ViewWarpResult::Status::kOk);
  int differ = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      differ += std::isnan(coarse_out.at<float>(y, x)) !=
                std::isnan(exact_out.at<float>(y, x));
  EXPECT_LT(differ, kW * kH / 500) << differ;
  EXPECT_NEAR(coarse.seen_share, every.seen_share, 0.002);
}

TEST(ViewWarp, ACameraLookingAwayIsOutOfView) {
  const Scene scene = testing::BoxAndPole().Build();
  const Camera reference = LookAt({3, -11, 8}, {0, 0, 0}, kW, kH);
  const Camera away = LookAt({3, -11, 8}, {3, -30, 12}, kW, kH);
  const cv::Mat frame(kH, kW, CV_32FC1, cv::Scalar(0.5f));
  const ViewWarp warp(scene, reference);
  cv::Mat out;
  const ViewWarpResult r = warp.Warp(frame, away, &out);
  EXPECT_EQ(r.status, ViewWarpResult::Status::kOutOfView);
  EXPECT_NE(r.message.find("% of the model"), std::string::npos) << r.message;
  EXPECT_LT(r.seen_share, 0.2);
}

TEST(ViewWarp, RefusesAFrameOfAnotherSizeAndACameraThatSeesNothing) {
  const Scene scene = testing::BoxAndPole().Build();
  const Camera reference = LookAt({3, -11, 8}, {0, 0, 0}, kW, kH);
  const ViewWarp warp(scene, reference);
  cv::Mat out;
  EXPECT_THROW(
      warp.Warp(cv::Mat(10, 10, CV_32FC1, cv::Scalar(0.f)), reference, &out),
      std::invalid_argument);
  EXPECT_EQ(warp.Warp(cv::Mat(), reference, &out).status,
            ViewWarpResult::Status::kNoFrame);
  EXPECT_THROW(ViewWarp(scene, LookAt({0, 0, 30}, {0, 0, 60}, kW, kH)),
               std::invalid_argument);
}

TEST(WarpedSource, FramesWithoutAPoseOrOutOfViewComeOutUnusableWithTheReason) {
  const Scene scene = testing::BoxAndPole().Build();
  const Camera reference = LookAt({3, -11, 8}, {0, 0, 0}, kW, kH);
  const Camera away = LookAt({3, -11, 8}, {3, -30, 12}, kW, kH);
  std::vector<StreamedFrame> frames(4);
  for (int i = 0; i < 4; ++i) {
    frames[i].index = i;
    frames[i].status = StreamedFrame::Status::kOk;
    frames[i].gray = RenderLambertian(scene, reference, kDown, Flat());
    frames[i].luma = cv::Mat(kH, kW, CV_8UC1, cv::Scalar(1));
  }
  FrameList list(std::move(frames));
  const ViewWarp warp(scene, reference);
  WarpedSource source(&list, &warp,
                      {reference, std::nullopt, away, std::nullopt},
                      {"", "", "", "the solve jumps here"});
  StreamedFrame f;
  ASSERT_TRUE(source.Next(&f));
  EXPECT_EQ(f.status, StreamedFrame::Status::kOk);
  EXPECT_TRUE(f.luma.empty());  // the unwarped 8-bit frame is not handed on
  EXPECT_EQ(f.gray.cols, kW);
  ASSERT_TRUE(source.Next(&f));
  EXPECT_EQ(f.status, StreamedFrame::Status::kUnusable);
  EXPECT_NE(f.message.find("no pose"), std::string::npos);
  ASSERT_TRUE(source.Next(&f));
  EXPECT_EQ(f.status, StreamedFrame::Status::kUnusable);
  EXPECT_NE(f.message.find("of the model"), std::string::npos);
  ASSERT_TRUE(source.Next(&f));
  EXPECT_EQ(f.status, StreamedFrame::Status::kUnusable);
  EXPECT_EQ(f.message, "the solve jumps here");
  EXPECT_FALSE(source.Next(&f));
}

TEST(WarpedSource, ResamplesOnTheCallersThreadOrAheadAlikeAndPassesErrorsOn) {
  const Scene scene = testing::BoxAndPole().Build();
  const Camera reference = LookAt({3, -11, 8}, {0, 0, 0}, kW, kH);
  const Camera moved = LookAt({-1, -11, 6}, {-1, 1, 0}, kW, kH);
  const ViewWarp warp(scene, reference);
  auto frames = [&](int count, int width) {
    std::vector<StreamedFrame> out(count);
    for (int i = 0; i < count; ++i) {
      out[i].index = i;
      out[i].status = StreamedFrame::Status::kOk;
      out[i].gray = width == kW ? RenderLambertian(scene, moved, kDown, Flat())
                                : cv::Mat(kH, width, CV_32FC1, cv::Scalar(0.f));
    }
    return out;
  };
  std::vector<cv::Mat> got[2];
  for (int queue : {0, 2}) {
    FrameList list(frames(5, kW));
    WarpedSource source(
        &list, &warp, std::vector<std::optional<Camera>>(5, moved), {}, queue);
    StreamedFrame f;
    while (source.Next(&f)) got[queue > 0].push_back(f.gray);
    EXPECT_GT(source.seconds(), 0.0);
  }
  ASSERT_EQ(got[0].size(), 5u);
  ASSERT_EQ(got[1].size(), 5u);
  for (int i = 0; i < 5; ++i) {
    int same = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const float a = got[0][i].at<float>(y, x),
                    b = got[1][i].at<float>(y, x);
        same += a == b || (std::isnan(a) && std::isnan(b));
      }
    EXPECT_EQ(same, kW * kH);
  }
  // A frame of another size than its camera's: the warp's error, in Next.
  FrameList wrong(frames(3, kW / 2));
  WarpedSource source(&wrong, &warp,
                      std::vector<std::optional<Camera>>(3, moved));
  StreamedFrame f;
  EXPECT_THROW(source.Next(&f), std::invalid_argument);
  // Destroyed with frames still queued: the thread stops.
  FrameList many(frames(8, kW));
  WarpedSource early(&many, &warp,
                     std::vector<std::optional<Camera>>(8, moved));
  ASSERT_TRUE(early.Next(&f));
}

}  // namespace
}  // namespace sunlapse
