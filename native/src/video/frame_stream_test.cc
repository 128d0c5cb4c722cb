#include "sunlapse/video/frame_stream.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

namespace sunlapse {
namespace {
namespace fs = std::filesystem;

// A numbered PNG sequence in a folder of its own, removed afterwards.
class Sequence {
 public:
  Sequence(const std::string& name, int count) {
    dir_ = fs::temp_directory_path() /
           ("sunlapse_stream_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (int i = 0; i < count; ++i)
      cv::imwrite(Path(i), cv::Mat(12, 16, CV_8UC3, cv::Scalar(10 * i, 0, 0)));
  }
  ~Sequence() { fs::remove_all(dir_); }
  std::string Path(int i) const {
    char name[32];
    std::snprintf(name, sizeof(name), "f_%03d.png", i + 1);
    return (dir_ / name).string();
  }

 private:
  fs::path dir_;
};

// Blue 10*i -> gray 0.114*10*i (OpenCV's BGR2GRAY, rounded) -> linear.
float Expected(int i, double gamma) {
  const cv::Mat px(1, 1, CV_8UC3, cv::Scalar(10 * i, 0, 0));
  return ToLinearGray(px, gamma).at<float>(0, 0);
}

TEST(FrameStream, HandsOutTheFramesAskedInTheirOrderAsLinearGray) {
  const Sequence seq("order", 6);
  FrameStreamOptions o;
  o.queue_frames = 1;
  o.gamma = 2.2;
  FrameStream s(seq.Path(0), {4, 5, 0, 1, 2}, o);
  EXPECT_EQ(s.width(), 16);
  std::vector<int> got;
  StreamedFrame f;
  while (s.Next(&f)) {
    ASSERT_EQ(f.status, StreamedFrame::Status::kOk) << f.message;
    ASSERT_EQ(f.gray.type(), CV_32F);
    EXPECT_TRUE(f.bgr.empty());
    EXPECT_NEAR(f.gray.at<float>(3, 3), Expected(f.index, 2.2), 1e-6);
    got.push_back(f.index);
  }
  EXPECT_EQ(got, (std::vector<int>{4, 5, 0, 1, 2}));
  EXPECT_FALSE(s.Next(&f));
}

TEST(FrameStream, ReducesFramesToTheSizeAsked) {
  const Sequence seq("reduce", 3);
  FrameStreamOptions o;
  o.width = 8;
  o.height = 6;
  FrameStream s(seq.Path(0), {0, 1, 2}, o);
  EXPECT_EQ(s.width(), 16);  // the clip's own size
  StreamedFrame f;
  int n = 0;
  while (s.Next(&f)) {
    ASSERT_EQ(f.status, StreamedFrame::Status::kOk) << f.message;
    ASSERT_EQ(f.gray.size(), cv::Size(8, 6));
    EXPECT_NEAR(f.gray.at<float>(3, 3), Expected(f.index, 2.2), 1e-6);
    ++n;
  }
  EXPECT_EQ(n, 3);
}

// Colour comes scaled as it is converted, gray from the same frame at its
// own size.
TEST(FrameStream, GivesColourScaledAndGrayFromTheSameFrame) {
  const Sequence seq("colour", 3);
  FrameStreamOptions o;
  o.keep_bgr = true;
  o.bgr_width = 4;
  o.bgr_height = 3;
  o.width = 8;
  o.height = 6;
  FrameStream s(seq.Path(0), {2, 0}, o);
  StreamedFrame f;
  for (int expected : {2, 0}) {
    ASSERT_TRUE(s.Next(&f));
    ASSERT_EQ(f.status, StreamedFrame::Status::kOk) << f.message;
    EXPECT_EQ(f.index, expected);
    ASSERT_EQ(f.bgr.size(), cv::Size(4, 3));
    ASSERT_EQ(f.gray.size(), cv::Size(8, 6));
    EXPECT_NEAR(f.bgr.at<cv::Vec3b>(1, 1)[0], 10 * expected, 1);
    EXPECT_NEAR(f.gray.at<float>(3, 3), Expected(expected, 2.2), 1e-6);
  }
  o.bgr_width = 4;
  o.bgr_height = 0;
  EXPECT_THROW(FrameStream(seq.Path(0), {0}, o), std::invalid_argument);
}

// Buffers are reused once the consumer lets go of them, never before.
TEST(FrameStream, FramesTheConsumerKeepsAreNeverOverwritten) {
  const Sequence seq("keep", 12);
  FrameStreamOptions o;
  o.queue_frames = 1;
  FrameStream s(seq.Path(0), {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, o);
  std::vector<cv::Mat> kept;
  StreamedFrame f;
  int n = 0;
  while (s.Next(&f)) {
    if (n++ % 2 == 0) kept.push_back(f.gray);  // every other one let go
  }
  ASSERT_EQ(kept.size(), 6u);
  for (size_t i = 0; i < kept.size(); ++i) {
    EXPECT_NEAR(kept[i].at<float>(5, 5), Expected(2 * static_cast<int>(i), 2.2),
                1e-6)
        << i;
  }
}

TEST(FrameStream, SaysWhyAFrameIsMissingAndGoesOn) {
  const Sequence seq("gaps", 4);
  std::ofstream(seq.Path(1)) << "not a png";
  FrameStreamOptions o;
  o.keep_bgr = true;
  FrameStream s(seq.Path(0), {0, 1, 2, 9}, o);
  StreamedFrame f;
  ASSERT_TRUE(s.Next(&f));
  EXPECT_EQ(f.status, StreamedFrame::Status::kOk);
  EXPECT_EQ(f.bgr.type(), CV_8UC3);
  ASSERT_TRUE(s.Next(&f));
  EXPECT_EQ(f.status, StreamedFrame::Status::kUnusable);
  EXPECT_TRUE(f.gray.empty());
  EXPECT_FALSE(f.message.empty());
  ASSERT_TRUE(s.Next(&f));
  EXPECT_EQ(f.index, 2);
  EXPECT_EQ(f.status, StreamedFrame::Status::kOk);
  ASSERT_TRUE(s.Next(&f));
  EXPECT_EQ(f.status, StreamedFrame::Status::kPastEnd);
  EXPECT_NE(f.message.find("10"), std::string::npos) << f.message;
  EXPECT_FALSE(s.Next(&f));
}

// An H.264 movie at 25 frames/s whose frame N has blue `blue_per_frame` x N,
// with a key frame every `gop`; false without ffmpeg and libx264.
bool MakeMovie(const std::string& path, int frames, int gop,
               int blue_per_frame) {
  const std::string g = std::to_string(gop);
  const std::string cmd =
      "ffmpeg -v error -y -f lavfi -i \"color=c=black:s=32x24:r=25:d=" +
      std::to_string(frames / 25.0) + ",geq=r=0:g=0:b='" +
      std::to_string(blue_per_frame) + "*N'\" -c:v libx264 -g " + g +
      " -keyint_min " + g + " -sc_threshold 0 -pix_fmt yuv444p " + path +
      " >/dev/null 2>&1";
  return std::system(cmd.c_str()) == 0;
}

TEST(FrameStream, NearFramesAreNewKeyFramesElseExact) {
  const Sequence seq("near", 1);  // for its folder
  // 120 frames whose blue channel is 2 x their index, a key frame every 30.
  const std::string movie = seq.Path(0) + ".mp4";
  if (!MakeMovie(movie, 120, 30, 2)) GTEST_SKIP() << "no ffmpeg with libx264";
  FrameStreamOptions o;
  o.near = true;
  o.near_min_frames = 8;  // 4 distinct key frames: not enough
  FrameStream s(movie, {5, 40, 45, 100}, o);
  std::vector<int> got;
  StreamedFrame f;
  while (s.Next(&f)) {
    ASSERT_EQ(f.status, StreamedFrame::Status::kOk) << f.message;
    got.push_back(f.index);
  }
  // 40's key frame (30) is new; 45's is 30 again, so 45 itself.
  EXPECT_EQ(got, (std::vector<int>{0, 30, 45, 90}));
  // With enough distinct key frames, only they are read.
  o.near_min_frames = 3;
  FrameStream keys(movie, {5, 40, 45, 100}, o);
  EXPECT_EQ(keys.size(), 3);
  got.clear();
  while (keys.Next(&f)) got.push_back(f.index);
  EXPECT_EQ(got, (std::vector<int>{0, 30, 90}));
}

// A long-GOP movie's key frames (near, enough of them) are shared out
// among several readers: in the order asked, each exactly what one reader
// decodes.
TEST(FrameStream, SharesAMoviesKeyFramesAmongReadersInOrder) {
  const Sequence seq("keys", 1);  // for its folder
  // 240 frames whose blue channel is their index, a key frame every 10.
  const std::string movie = seq.Path(0) + ".mp4";
  if (!MakeMovie(movie, 240, 10, 1)) GTEST_SKIP() << "no ffmpeg with libx264";
  std::vector<int> indices;
  for (int i = 0; i < 24; ++i) indices.push_back(10 * i + 3);
  auto read_all = [&](int threads) {
    FrameStreamOptions o;
    o.near = true;
    o.decode_threads = threads;
    o.queue_frames = 2;
    FrameStream s(movie, indices, o);
    std::vector<std::pair<int, float>> got;
    StreamedFrame f;
    while (s.Next(&f)) {
      EXPECT_EQ(f.status, StreamedFrame::Status::kOk) << f.message;
      got.emplace_back(f.index, f.gray.empty() ? -1.f : f.gray.at<float>(5, 5));
    }
    return got;
  };
  const auto one = read_all(1), three = read_all(3);
  ASSERT_EQ(one.size(), 24u);
  for (int i = 0; i < 24; ++i) EXPECT_EQ(one[i].first, 10 * i) << i;
  EXPECT_EQ(three, one);
  // Each key frame's own picture: frame 10 i is brighter than 10 (i - 1).
  for (int i = 1; i < 24; ++i) EXPECT_GT(one[i].second, one[i - 1].second) << i;
}

TEST(FrameStream, DecodesASequenceOnSeveralThreadsInOrder) {
  // Stills are independent: several threads decode them side by side, and
  // the frames still come out in the order asked, each exactly what one
  // thread gives, a missing file at its own place.
  const Sequence seq("threads", 40);
  fs::remove(seq.Path(17));
  std::vector<int> indices;
  for (int i = 0; i < 40; ++i) indices.push_back(i);
  std::swap(indices[3], indices[30]);  // and not only forward
  auto read_all = [&](int threads) {
    FrameStreamOptions o;
    o.queue_frames = 2;
    o.decode_threads = threads;
    FrameStream s(seq.Path(0), indices, o);
    std::vector<StreamedFrame> out;
    StreamedFrame f;
    while (s.Next(&f)) out.push_back(f);
    return out;
  };
  const std::vector<StreamedFrame> one = read_all(1);
  for (int threads : {2, 3, 8}) {
    const std::vector<StreamedFrame> many = read_all(threads);
    ASSERT_EQ(many.size(), indices.size());
    for (size_t k = 0; k < indices.size(); ++k) {
      EXPECT_EQ(many[k].index, indices[k]) << threads;
      EXPECT_EQ(many[k].status, one[k].status) << k;
      if (indices[k] == 17) {
        EXPECT_EQ(many[k].status, StreamedFrame::Status::kUnusable);
      } else {
        ASSERT_EQ(many[k].status, StreamedFrame::Status::kOk) << k;
        EXPECT_EQ(cv::norm(many[k].gray, one[k].gray, cv::NORM_INF), 0.0);
      }
    }
  }
}

TEST(FrameStream, StopsWhenDroppedHalfWay) {
  const Sequence seq("drop", 8);
  FrameStreamOptions o;
  o.queue_frames = 2;
  {
    FrameStream s(seq.Path(0), {0, 1, 2, 3, 4, 5, 6, 7}, o);
    StreamedFrame f;
    ASSERT_TRUE(s.Next(&f));
  }  // the decoding thread, blocked on a full queue, is joined here (a
     // deadlock fails the test by ctest's timeout)
}

TEST(FrameStream, RefusesBadOptionsAndMissingFiles) {
  const Sequence seq("bad", 1);
  FrameStreamOptions o;
  o.queue_frames = 0;
  EXPECT_THROW(FrameStream(seq.Path(0), {0}, o), std::invalid_argument);
  o = FrameStreamOptions();
  o.width = 8;  // and no height
  EXPECT_THROW(FrameStream(seq.Path(0), {0}, o), std::invalid_argument);
  EXPECT_THROW(FrameStream("/nonexistent/clip.mp4", {0}, FrameStreamOptions()),
               std::invalid_argument);
}

}  // namespace
}  // namespace sunlapse
