#include "sunlapse/whole_clip/clip_pass.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "sunlapse/common/angles.h"
#include "sunlapse/video/video_reader.h"
#include "synthetic.h"

namespace sunlapse {
namespace {

Eigen::Vector3d PathAt(int f, int n) {
  const double t = static_cast<double>(f) / (n - 1);
  return SunInWorldFromAngles(55 - 20 * t, 110 + 50 * t);
}

struct Fixture {
  Scene scene = testing::BenchScene().Build();
  Camera cam = testing::LookAt({4, -12, 9}, {0, 0, 0}, 320, 240);
  int n = 16;
  std::vector<cv::Mat> frames;
  SkyEvidence sky{scene, cam, SkyEvidenceOptions()};
  ShadowTracker tracker{scene, cam, [] {
                          ShadowTrackerOptions o;
                          o.ground_object_ids = {0};
                          return o;
                        }()};
  Fixture() {
    for (int f = 0; f < n; ++f)
      frames.push_back(testing::RenderLambertian(
          scene, cam, PathAt(f, n), testing::TexturedGround(f + 1)));
    sky.SetReference({frames[0], frames[5], frames[10], frames[15]});
  }
  // The frames as a source; frame `broken` undecodable, `small` too small.
  // with_luma: as a movie's stream gives them, 8-bit luma and its table
  // beside the linear gray made from them.
  FrameList Source(int broken, int small, bool with_luma = false) const {
    std::vector<StreamedFrame> list;
    const cv::Mat table = LinearGrayTable(2.2);
    for (int f = 0; f < n; ++f) {
      StreamedFrame s;
      s.index = f;
      s.status = StreamedFrame::Status::kOk;
      s.gray = frames[f];
      if (with_luma) {
        cv::Mat encoded;
        cv::pow(frames[f], 1.0 / 2.2, encoded);
        encoded.convertTo(s.luma, CV_8U, 255.0);
        s.table = table;
        cv::LUT(s.luma, table, s.gray);
      }
      if (f == broken) {
        s.status = StreamedFrame::Status::kUnusable;
        s.gray = cv::Mat();
        s.message = "corrupt packet";
      }
      if (f == small) s.gray = cv::Mat(10, 10, CV_32F, cv::Scalar(0.5));
      list.push_back(s);
    }
    return FrameList(std::move(list));
  }
  std::vector<int> Indices() const {
    std::vector<int> v;
    for (int f = 0; f < n; ++f) v.push_back(f);
    return v;
  }
};

TEST(ClipPass, ScoresEveryFrameAndFollowsTheSunThroughBrokenFrames) {
  Fixture fx;
  // Frame 3 was read before (kept): the source does not give it again.
  std::vector<cv::Mat> kept(fx.n);
  kept[3] = fx.frames[3];
  std::vector<StreamedFrame> rest;
  FrameList all = fx.Source(/*broken=*/6, /*small=*/9);
  for (StreamedFrame s; all.Next(&s);)
    if (s.index != 3) rest.push_back(s);
  FrameList source(std::move(rest));
  const ClipPassResult r =
      RunClipPass(&source, fx.Indices(), kept, {}, fx.cam, &fx.sky, &fx.tracker,
                  ClipPassOptions(), nullptr);
  ASSERT_EQ(r.status, ClipPassResult::Status::kSuccess);
  ASSERT_EQ(r.frames.size(), static_cast<size_t>(fx.n));
  EXPECT_TRUE(r.tracker_started);
  EXPECT_EQ(r.frames[6].read_message, "corrupt packet");
  EXPECT_NE(r.frames[9].read_message.find("not the camera's 320x240"),
            std::string::npos)
      << r.frames[9].read_message;
  for (int f = 0; f < fx.n; ++f) {
    const ClipPassFrame& pf = r.frames[f];
    EXPECT_EQ(pf.index, f);
    if (f == 6 || f == 9) {
      EXPECT_FALSE(pf.tracked) << f;
      EXPECT_EQ(pf.evidence.status, FrameEvidence::Status::kNoFrame) << f;
      continue;
    }
    EXPECT_EQ(pf.evidence.status, FrameEvidence::Status::kOk) << f;
    ASSERT_TRUE(pf.tracked) << f << ": " << pf.track.reason;
    EXPECT_LT(AngleBetweenDeg(pf.track.sun_in_world, PathAt(f, fx.n)), 1.0)
        << "frame " << f;
  }
  EXPECT_EQ(fx.sky.num_frames(), fx.n);
}

// Frames the check may want again are kept, up to a number: a frame the
// caller gave as a copy (never a view of it), a frame the source gave with
// its 8-bit luma as that luma, which gives back exactly the frame tracked.
TEST(ClipPass, KeepsFramesTrackedAwayFromTheirEvidenceUpToANumber) {
  Fixture fx;
  std::vector<cv::Mat> kept(fx.n);
  kept[0] = fx.frames[0];
  std::vector<StreamedFrame> rest, given(fx.n);
  FrameList all = fx.Source(-1, -1, /*with_luma=*/true);
  for (StreamedFrame s; all.Next(&s);) {
    given[s.index] = s;
    if (s.index != 0) rest.push_back(s);
  }
  FrameList source(std::move(rest));
  ClipPassOptions o;
  o.keep_off_deg = 0.0;  // every frame is "away" from its evidence
  o.keep_max_frames = 3;
  const ClipPassResult r = RunClipPass(&source, fx.Indices(), kept, {}, fx.cam,
                                       &fx.sky, &fx.tracker, o, nullptr);
  for (int f = 0; f < fx.n; ++f) {
    const ClipPassFrame& pf = r.frames[f];
    const cv::Mat g = pf.Kept();
    EXPECT_EQ(g.empty(), f >= 3) << f;
    if (g.empty()) continue;
    EXPECT_EQ(g.type(), CV_32F);
    EXPECT_EQ(g.size(), cv::Size(fx.cam.width(), fx.cam.height()));
    const cv::Mat& tracked = f == 0 ? fx.frames[0] : given[f].gray;
    EXPECT_EQ(cv::norm(g, tracked, cv::NORM_INF), 0.0) << f;
    // From the source: the luma (a byte a pixel), not a float copy.
    EXPECT_EQ(pf.kept_gray.empty(), f > 0) << f;
    EXPECT_EQ(pf.kept_luma.empty(), f == 0) << f;
  }
  EXPECT_NE(r.frames[0].kept_gray.data, fx.frames[0].data);

  Fixture again;
  FrameList clean = again.Source(-1, -1);
  o.keep_off_deg = 180.0;  // only frames the tracker did not follow
  const ClipPassResult none =
      RunClipPass(&clean, again.Indices(), std::vector<cv::Mat>(again.n), {},
                  again.cam, &again.sky, &again.tracker, o, nullptr);
  for (int f = 0; f < again.n; ++f)
    EXPECT_EQ(none.frames[f].Kept().empty(), none.frames[f].tracked) << f;
}

TEST(ClipPass, StopsWhenAskedAndRefusesAMismatchedSource) {
  Fixture fx;
  FrameList source = fx.Source(-1, -1);
  int calls = 0;
  const ClipPassResult r = RunClipPass(
      &source, fx.Indices(), std::vector<cv::Mat>(fx.n), {}, fx.cam, &fx.sky,
      &fx.tracker, ClipPassOptions(), [&](double) { return ++calls < 2; });
  EXPECT_EQ(r.status, ClipPassResult::Status::kCancelled);
  EXPECT_LT(r.frames.size(), static_cast<size_t>(fx.n));
  FrameList other = fx.Source(-1, -1);
  std::vector<int> shifted = fx.Indices();
  shifted[0] = 5;
  EXPECT_THROW(
      RunClipPass(&other, shifted, std::vector<cv::Mat>(fx.n), {}, fx.cam,
                  &fx.sky, &fx.tracker, ClipPassOptions(), nullptr),
      std::runtime_error);
}

}  // namespace
}  // namespace sunlapse
