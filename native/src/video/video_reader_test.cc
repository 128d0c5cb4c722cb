#include "sunlapse/video/video_reader.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

namespace sunlapse {
namespace {
namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() /
                     ("sunlapse_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

cv::Mat Frame(int i) {
  return cv::Mat(24, 32, CV_8UC3, cv::Scalar(10 * i, 20, 30));
}

TEST(VideoReader, ReadsANumberedSequenceFromItsFirstFile) {
  const fs::path d = TempDir("seq");
  for (int i = 0; i < 4; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "f_%03d.png", 7 + i);
    cv::imwrite((d / name).string(), Frame(i));
  }
  VideoReader r((d / "f_007.png").string());
  EXPECT_TRUE(r.is_sequence());
  EXPECT_EQ(r.num_frames(), 4);
  EXPECT_EQ(r.width(), 32);
  cv::Mat f;
  int n = 0;
  while (r.Read(&f)) {
    ASSERT_FALSE(f.empty());
    EXPECT_EQ(f.at<cv::Vec3b>(0, 0)[0], 10 * n);
    ++n;
  }
  EXPECT_EQ(n, 4);
  ASSERT_TRUE(r.Seek(2));
  ASSERT_TRUE(r.Read(&f));
  EXPECT_EQ(f.at<cv::Vec3b>(0, 0)[0], 20);
}

TEST(VideoReader, CorruptFrameComesBackEmptyAndReadingGoesOn) {
  const fs::path d = TempDir("corrupt");
  cv::imwrite((d / "f_1.png").string(), Frame(0));
  std::ofstream(d / "f_2.png") << "not a png";
  cv::imwrite((d / "f_3.png").string(), Frame(2));
  VideoReader r((d / "f_1.png").string());
  cv::Mat f;
  ASSERT_TRUE(r.Read(&f));
  EXPECT_FALSE(f.empty());
  ASSERT_TRUE(r.Read(&f));
  EXPECT_TRUE(f.empty());
  ASSERT_TRUE(r.Read(&f));
  EXPECT_FALSE(f.empty());
  EXPECT_FALSE(r.Read(&f));
}

TEST(VideoReader, ReadsAMovieFile) {
  const fs::path d = TempDir("movie");
  const std::string path = (d / "clip.avi").string();
  {
    cv::VideoWriter w(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                      cv::Size(32, 24));
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 5; ++i) w.write(Frame(i * 4));
  }
  VideoReader r(path);
  EXPECT_FALSE(r.is_sequence());
  EXPECT_EQ(r.width(), 32);
  cv::Mat f;
  int n = 0;
  while (r.Read(&f)) n += !f.empty();
  EXPECT_EQ(n, 5);
}

TEST(VideoReader, MissingOrUndecodableFilesThrow) {
  EXPECT_THROW(VideoReader("/nonexistent/clip.mp4"), std::invalid_argument);
  const fs::path d = TempDir("bad");
  std::ofstream(d / "clip.mp4") << "garbage";
  EXPECT_THROW(VideoReader((d / "clip.mp4").string()), std::invalid_argument);
}

TEST(VideoReader, LinearGrayUndoesGamma) {
  cv::Mat img(1, 1, CV_8UC3, cv::Scalar(128, 128, 128));
  const cv::Mat g = ToLinearGray(img, 2.2);
  EXPECT_NEAR(g.at<float>(0, 0), std::pow(128 / 255.0, 2.2), 1e-4);
  EXPECT_NEAR(ToLinearGray(img, 1.0).at<float>(0, 0), 128 / 255.0, 1e-6);
}

}  // namespace
}  // namespace sunlapse
