#include "sunlapse/video/video_reader.h"
#include "temp_dir.h"
#include "tiff_plain.h"

#include <gtest/gtest.h>

#include <sys/resource.h>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

namespace sunlapse {
namespace {
namespace fs = std::filesystem;

using testing::TempDir;

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

TEST(VideoReader, ReadsGrayWithoutColourConversionCloseToBgrsGray) {
  const fs::path d = TempDir("gray");
  cv::Mat img(24, 32, CV_8UC3);
  cv::randu(img, 0, 255);
  cv::imwrite((d / "g_1.png").string(), img);
  cv::imwrite((d / "g_2.png").string(), img);
  VideoReader r((d / "g_1.png").string());
  cv::Mat bgr, gray, expected;
  ASSERT_TRUE(r.Read(&bgr));
  ASSERT_TRUE(r.ReadGray(&gray));
  ASSERT_EQ(gray.type(), CV_8UC1);
  cv::cvtColor(bgr, expected, cv::COLOR_BGR2GRAY);
  cv::Mat diff;
  cv::absdiff(gray, expected, diff);
  double worst = 0;
  cv::minMaxLoc(diff, nullptr, &worst);
  EXPECT_LE(worst, 2.0);
}

// A horizontal ramp of grays, black to white.
cv::Mat Ramp(int width, int height) {
  cv::Mat img(height, width, CV_8UC3);
  for (int x = 0; x < width; ++x)
    img.col(x).setTo(cv::Scalar::all(255.0 * x / (width - 1)));
  return img;
}

// Movies whose decoder gives planar YUV are read as gray from the luma
// plane itself: full range (MJPEG) as it is, video range (MPEG-4) expanded
// to 0-255 as the colour conversion does.
TEST(VideoReader, ReadsGrayFromTheLumaPlaneInTheColourConversionsRange) {
  const fs::path d = TempDir("luma");
  for (const char* fourcc : {"MJPG", "mp4v"}) {
    const std::string path = (d / (std::string(fourcc) + ".avi")).string();
    {
      cv::VideoWriter w(
          path,
          cv::VideoWriter::fourcc(fourcc[0], fourcc[1], fourcc[2], fourcc[3]),
          25, cv::Size(64, 48));
      ASSERT_TRUE(w.isOpened()) << fourcc;
      for (int i = 0; i < 3; ++i) w.write(Ramp(64, 48));
    }
    VideoReader bgr_reader(path), gray_reader(path);
    cv::Mat bgr, gray, expected, diff;
    ASSERT_TRUE(bgr_reader.Read(&bgr));
    ASSERT_TRUE(gray_reader.ReadGray(&gray));
    ASSERT_EQ(gray.type(), CV_8UC1);
    cv::cvtColor(bgr, expected, cv::COLOR_BGR2GRAY);
    cv::absdiff(gray, expected, diff);
    double worst = 0, black = 0, white = 0;
    cv::minMaxLoc(diff, nullptr, &worst);
    EXPECT_LE(worst, 3.0) << fourcc;
    cv::minMaxLoc(gray, &black, &white);
    EXPECT_LE(black, 4.0) << fourcc;
    EXPECT_GE(white, 251.0) << fourcc;
  }
}

TEST(VideoReader, ReadsGrayReducedByAreaAveraging) {
  const fs::path d = TempDir("reduced");
  const std::string path = (d / "clip.avi").string();
  {
    cv::VideoWriter w(path, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), 25,
                      cv::Size(64, 48));
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 3; ++i) w.write(Ramp(64, 48));
  }
  VideoReader full_reader(path), reduced_reader(path);
  cv::Mat full, reduced, diff;
  ASSERT_TRUE(full_reader.ReadGray(&full));
  ASSERT_TRUE(reduced_reader.ReadGray(&reduced, cv::Size(16, 12)));
  ASSERT_EQ(reduced.size(), cv::Size(16, 12));
  // Reduced, then the range expanded: one level of rounding apart.
  cv::absdiff(reduced, AreaReduced(full, cv::Size(16, 12)), diff);
  double worst = 0;
  cv::minMaxLoc(diff, nullptr, &worst);
  EXPECT_LE(worst, 1.0);
  // Colour scaled in the conversion itself, gray of the same frame.
  VideoReader both_reader(path), bgr_reader(path);
  cv::Mat gray, small_bgr, bgr;
  ASSERT_TRUE(both_reader.ReadGrayAndBgr(&gray, cv::Size(), &small_bgr,
                                         cv::Size(16, 12)));
  ASSERT_TRUE(bgr_reader.Read(&bgr));
  EXPECT_EQ(cv::norm(gray, full, cv::NORM_INF), 0.0);
  ASSERT_EQ(small_bgr.size(), cv::Size(16, 12));
  cv::absdiff(small_bgr, AreaReduced(bgr, cv::Size(16, 12)), diff);
  cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
  EXPECT_LE(worst, 6.0);
}

TEST(VideoReader, Reads16BitTiffStillsAsTheir8BitTwins) {
  // A raw converter's 16-bit TIFF export: gray from its own path, reduced
  // before it is weighed; the same pictures in 8 bits go through swscale.
  const fs::path d = TempDir("tiff16");
  cv::Mat colour(96, 128, CV_8UC3);
  cv::randu(colour, cv::Scalar::all(0), cv::Scalar::all(256));
  cv::GaussianBlur(colour, colour, cv::Size(9, 9), 3);
  for (int i = 1; i <= 2; ++i) {
    cv::Mat deep;
    colour.convertTo(deep, CV_16UC3, 257.0);
    ASSERT_TRUE(cv::imwrite(
        (d / ("deep_000" + std::to_string(i) + ".tif")).string(), deep));
    ASSERT_TRUE(cv::imwrite(
        (d / ("flat_000" + std::to_string(i) + ".png")).string(), colour));
  }
  for (cv::Size size : {cv::Size(), cv::Size(32, 24), cv::Size(50, 37)}) {
    VideoReader deep((d / "deep_0001.tif").string()),
        flat((d / "flat_0001.png").string());
    for (int i = 0; i < 2; ++i) {
      cv::Mat a, b;
      ASSERT_TRUE(deep.ReadGray(&a, size));
      ASSERT_TRUE(flat.ReadGray(&b, size));
      ASSERT_EQ(deep.last_frame().status, FrameStatus::kOk);
      ASSERT_EQ(a.type(), CV_8UC1);
      ASSERT_EQ(a.size(), size.empty() ? cv::Size(128, 96) : size);
      EXPECT_LE(cv::norm(a, b, cv::NORM_INF), 2.0) << size;
    }
  }
  // A still of another size is reported as before.
  cv::Mat other(48, 64, CV_16UC3, cv::Scalar::all(30000));
  ASSERT_TRUE(cv::imwrite((d / "deep_0002.tif").string(), other));
  VideoReader deep((d / "deep_0001.tif").string());
  cv::Mat a;
  ASSERT_TRUE(deep.ReadGray(&a, cv::Size(32, 24)));
  ASSERT_TRUE(deep.ReadGray(&a, cv::Size(32, 24)));
  EXPECT_EQ(deep.last_frame().status, FrameStatus::kSizeChanged);
  EXPECT_TRUE(a.empty());
}

// A baseline TIFF written by hand: w x h, `channels` 16-bit samples a
// pixel, in strips of `rows` rows, in either byte order; pixel (x, y)'s
// sample c is 1000 * c + 10 * y + x.
void WriteTiff(const fs::path& path, bool big, int w, int h, int channels,
               int rows) {
  std::string out;
  auto put = [&](uint64_t v, int n) {
    for (int i = 0; i < n; ++i)
      out.push_back(static_cast<char>(v >> (8 * (big ? n - 1 - i : i))));
  };
  out += big ? "MM" : "II";
  put(42, 2);
  put(8, 4);  // the directory right after the header
  const int strips = (h + rows - 1) / rows, tags = 10;
  const uint64_t values = 8 + 2 + 12 * tags + 4;  // after the directory
  const uint64_t offsets_at = values, counts_at = offsets_at + 4 * strips,
                 bits_at = counts_at + 4 * strips,
                 data_at = bits_at + 2 * channels;
  auto entry = [&](int tag, int type, uint64_t n, uint64_t value) {
    put(tag, 2);
    put(type, 2);
    put(n, 4);
    if (type == 3 && n == 1) {
      put(value, 2);
      put(0, 2);
    } else {
      put(value, 4);
    }
  };
  put(tags, 2);
  entry(256, 3, 1, w);
  entry(257, 3, 1, h);
  entry(258, 3, channels, bits_at);
  entry(259, 3, 1, 1);
  entry(262, 3, 1, 2);
  entry(273, 4, strips, offsets_at);
  entry(277, 3, 1, channels);
  entry(278, 3, 1, rows);
  entry(279, 4, strips, counts_at);
  entry(284, 3, 1, 1);
  put(0, 4);  // no next directory
  const uint64_t row_bytes = 2ull * w * channels;
  for (int s = 0; s < strips; ++s) put(data_at + s * rows * row_bytes, 4);
  for (int s = 0; s < strips; ++s)
    put(std::min(rows, h - s * rows) * row_bytes, 4);
  for (int c = 0; c < channels; ++c) put(16, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) put(1000 * c + 10 * y + x, 2);
  std::ofstream(path, std::ios::binary) << out;
}

TEST(PlainTiff, ReadsEitherByteOrderRgbOrRgbaInStrips) {
  const fs::path d = TempDir("tiff_hand");
  for (bool big : {false, true}) {
    for (int channels : {3, 4}) {
      const fs::path path = d / "hand.tif";
      WriteTiff(path, big, 5, 3, channels, 2);
      PlainTiff tiff;
      ASSERT_EQ(tiff.Open(path.string(), 1 << 20), "") << big << channels;
      cv::Mat rgb;
      ASSERT_TRUE(tiff.Read(&rgb));
      ASSERT_EQ(rgb.type(), CV_16UC(channels));
      ASSERT_EQ(rgb.size(), cv::Size(5, 3));
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x)
          for (int c = 0; c < channels; ++c)
            ASSERT_EQ(rgb.ptr<uint16_t>(y)[channels * x + c],
                      1000 * c + 10 * y + x)
                << big << " " << channels << " " << x << "," << y;
      // Cut inside its last strip: refused at opening (FFmpeg then reports
      // the still), never read past the file's end.
      fs::resize_file(path, fs::file_size(path) - 2);
      EXPECT_EQ(tiff.Open(path.string(), 1 << 20), "a strip beyond the file");
      // Larger than allowed: refused before anything is read.
      WriteTiff(path, big, 5, 3, channels, 2);
      EXPECT_NE(tiff.Open(path.string(), 14), "");
    }
  }
}

TEST(VideoReader, ReadsUncompressedTiffStillsAsFfmpegReadsCompressedOnes) {
  // Uncompressed 16-bit TIFFs are read from their strips (tiff_plain.h);
  // the same pictures LZW-compressed go through FFmpeg: the same gray.
  const fs::path d = TempDir("tiff_plain");
  cv::Mat deep(96, 128, CV_16UC3);
  cv::randu(deep, cv::Scalar::all(0), cv::Scalar::all(65536));
  cv::GaussianBlur(deep, deep, cv::Size(9, 9), 3);
  const std::vector<int> plain = {cv::IMWRITE_TIFF_COMPRESSION, 1};
  const std::vector<int> lzw = {cv::IMWRITE_TIFF_COMPRESSION, 5};
  for (int i = 1; i <= 3; ++i) {
    const std::string n = "_000" + std::to_string(i) + ".tif";
    ASSERT_TRUE(cv::imwrite((d / ("plain" + n)).string(), deep, plain));
    ASSERT_TRUE(cv::imwrite((d / ("lzw" + n)).string(), deep, lzw));
  }
  // The plain reader takes the one and leaves the other to FFmpeg.
  PlainTiff tiff;
  ASSERT_EQ(tiff.Open((d / "plain_0001.tif").string(), 1 << 20), "");
  EXPECT_EQ(tiff.Open((d / "lzw_0001.tif").string(), 1 << 20), "compressed");
  for (cv::Size size : {cv::Size(), cv::Size(32, 24), cv::Size(50, 37)}) {
    VideoReader a((d / "plain_0001.tif").string()),
        b((d / "lzw_0001.tif").string());
    EXPECT_EQ(a.width(), 128);
    EXPECT_EQ(a.height(), 96);
    for (int i = 0; i < 3; ++i) {
      cv::Mat ga, gb, ca, cb;
      ASSERT_TRUE(a.ReadGrayAndBgr(&ga, size, &ca, cv::Size(32, 24)));
      ASSERT_TRUE(b.ReadGrayAndBgr(&gb, size, &cb, cv::Size(32, 24)));
      ASSERT_EQ(a.last_frame().status, FrameStatus::kOk);
      ASSERT_EQ(ga.type(), CV_8UC1);
      ASSERT_EQ(ga.size(), gb.size());
      EXPECT_EQ(cv::norm(ga, gb, cv::NORM_INF), 0.0) << size;
      ASSERT_EQ(ca.type(), CV_8UC3);
      EXPECT_LE(cv::norm(ca, cb, cv::NORM_INF), 2.0) << size;
    }
  }
  // A still cut short is reported as undecodable, and reading goes on.
  const fs::path cut = d / "plain_0002.tif";
  fs::resize_file(cut, fs::file_size(cut) / 2);
  VideoReader a((d / "plain_0001.tif").string());
  cv::Mat g;
  ASSERT_TRUE(a.ReadGray(&g, cv::Size(32, 24)));
  ASSERT_TRUE(a.ReadGray(&g, cv::Size(32, 24)));
  EXPECT_EQ(a.last_frame().status, FrameStatus::kUndecodable);
  EXPECT_TRUE(g.empty());
  ASSERT_TRUE(a.ReadGray(&g, cv::Size(32, 24)));
  EXPECT_EQ(a.last_frame().status, FrameStatus::kOk);
}

TEST(AreaReduced, HalvingsAreOneAreaAverage) {
  cv::Mat img(48, 64, CV_32F);
  cv::randu(img, 0.0, 1.0);
  for (const cv::Size size :
       {cv::Size(32, 24), cv::Size(16, 12), cv::Size(8, 6), cv::Size(24, 18)}) {
    cv::Mat direct, diff;
    cv::resize(img, direct, size, 0, 0, cv::INTER_AREA);
    const cv::Mat got = AreaReduced(img, size);
    ASSERT_EQ(got.size(), size);
    cv::absdiff(got, direct, diff);
    double worst = 0;
    cv::minMaxLoc(diff, nullptr, &worst);
    EXPECT_LT(worst, 1e-5) << size;
  }
  EXPECT_EQ(AreaReduced(img, img.size()).data, img.data);
  EXPECT_EQ(AreaReduced(img, cv::Size()).data, img.data);
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

TEST(VideoReader, AGapInASequenceIsReportedAndReadingGoesOn) {
  const fs::path d = TempDir("gap");
  for (int i : {1, 2, 4, 5}) {
    cv::imwrite((d / ("f_" + std::to_string(i) + ".png")).string(), Frame(i));
  }
  VideoReader r((d / "f_1.png").string());
  EXPECT_EQ(r.num_frames(), 5);  // the gap counts: frame numbers stay aligned
  cv::Mat f;
  std::vector<FrameStatus> statuses;
  std::vector<int> blues;
  while (r.Read(&f)) {
    statuses.push_back(r.last_frame().status);
    blues.push_back(f.empty() ? -1 : f.at<cv::Vec3b>(0, 0)[0]);
  }
  ASSERT_EQ(statuses.size(), 5u);
  EXPECT_EQ(statuses[2], FrameStatus::kMissingFile);
  EXPECT_EQ(statuses[4], FrameStatus::kOk);
  EXPECT_EQ(blues, (std::vector<int>{10, 20, -1, 40, 50}));
}

TEST(VideoReader, AFrameOfAnotherSizeIsReportedAndReadingGoesOn) {
  const fs::path d = TempDir("size");
  cv::imwrite((d / "f_01.png").string(), Frame(1));
  cv::imwrite((d / "f_02.png").string(),
              cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3)));
  cv::imwrite((d / "f_03.png").string(), Frame(3));
  VideoReader r((d / "f_01.png").string());
  cv::Mat f;
  ASSERT_TRUE(r.Read(&f) && r.Read(&f));
  EXPECT_TRUE(f.empty());
  EXPECT_EQ(r.last_frame().status, FrameStatus::kSizeChanged);
  EXPECT_EQ(r.last_frame().width, 64);
  EXPECT_EQ(r.last_frame().index, 1);
  ASSERT_TRUE(r.Read(&f));
  EXPECT_EQ(r.last_frame().status, FrameStatus::kOk);
  EXPECT_EQ(f.at<cv::Vec3b>(0, 0)[0], 30);
  EXPECT_FALSE(r.Read(&f));
}

// A movie whose frames' colour encodes their index, written by OpenCV.
std::string NumberedMovie(const fs::path& d, int n) {
  const std::string path = (d / "numbered.avi").string();
  cv::VideoWriter w(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                    cv::Size(32, 24));
  for (int i = 0; i < n; ++i) {
    w.write(cv::Mat(24, 32, CV_8UC3, cv::Scalar(2 * i, 100, 50)));
  }
  return path;
}

TEST(VideoReader, SeeksFarForwardAndBackToTheExactFrame) {
  const fs::path d = TempDir("seek");
  VideoReader r(NumberedMovie(d, 120));
  EXPECT_EQ(r.num_frames(), 120);
  cv::Mat f;
  for (int target : {100, 10, 60, 61, 119, 0}) {
    ASSERT_TRUE(r.Seek(target)) << target;
    ASSERT_TRUE(r.Read(&f)) << target;
    ASSERT_FALSE(f.empty());
    EXPECT_NEAR(f.at<cv::Vec3b>(12, 16)[0], 2 * target, 3) << target;
    EXPECT_EQ(r.last_frame().index, target);
  }
  EXPECT_FALSE(r.Seek(120));
  EXPECT_EQ(r.CountFrames(), 120);
}

// Runs the ffmpeg command line; false when it is missing or fails.
bool Ffmpeg(const std::string& args) {
  return std::system(
             ("ffmpeg -v error -y " + args + " >/dev/null 2>&1").c_str()) == 0;
}

// `frames` frames of a 128x96 ramp as MJPEG in d/ramp.avi (the source the
// ffmpeg-made clips are converted from); empty when it cannot be written.
std::string RampMovie(const fs::path& d, int frames) {
  const std::string path = (d / "ramp.avi").string();
  cv::VideoWriter w(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                    cv::Size(128, 96));
  if (!w.isOpened()) return {};
  for (int i = 0; i < frames; ++i) w.write(Ramp(128, 96));
  return path;
}

TEST(VideoReader, ReadsGrayFromA10BitLumaPlaneAsFromAn8BitOne) {
  // ProRes (10-bit 4:2:2) and 10-bit H.264 have their own luma path; the
  // same frames in 8 bits go through the 8-bit one.
  const fs::path d = TempDir("deep");
  const std::string src = RampMovie(d, 3);
  ASSERT_FALSE(src.empty());
  const std::string eight = (d / "eight.mkv").string();
  const std::string deep = (d / "deep.mov").string();
  if (!Ffmpeg("-i " + src + " -c:v ffv1 -pix_fmt yuv422p " + eight) ||
      !Ffmpeg("-i " + src +
              " -c:v prores_ks -profile:v 3 -pix_fmt yuv422p10le " + deep)) {
    GTEST_SKIP() << "ffmpeg with ffv1 and prores_ks is not available";
  }
  for (cv::Size size : {cv::Size(), cv::Size(32, 24), cv::Size(50, 37)}) {
    VideoReader a(eight), b(deep);
    cv::Mat ga, gb, diff;
    ASSERT_TRUE(a.ReadGray(&ga, size));
    ASSERT_TRUE(b.ReadGray(&gb, size));
    ASSERT_EQ(gb.type(), CV_8UC1);
    ASSERT_EQ(gb.size(), ga.size());
    cv::absdiff(ga, gb, diff);
    double worst = 0;
    cv::minMaxLoc(diff, nullptr, &worst);
    // ProRes is lossy; ffv1 is not: a few levels at the ramp's edges.
    EXPECT_LE(worst, 4.0) << size;
    EXPECT_LE(cv::mean(diff)[0], 1.0) << size;
    double black = 0, white = 0;
    cv::minMaxLoc(gb, &black, &white);
    EXPECT_LE(black, 6.0);
    EXPECT_GE(white, 249.0);
  }
}

TEST(VideoReader, AGrayOnlyReaderGivesTheSameGrayAndRefusesColour) {
  // ProRes skips its colour planes when asked for gray only: the luma must
  // not change, and nothing may hand out the planes it left undecoded.
  const fs::path d = TempDir("gray_only");
  const std::string src = RampMovie(d, 4);
  ASSERT_FALSE(src.empty());
  const std::string deep = (d / "deep.mov").string();
  if (!Ffmpeg("-i " + src +
              " -c:v prores_ks -profile:v 3 -pix_fmt yuv422p10le " + deep)) {
    GTEST_SKIP() << "ffmpeg with prores_ks is not available";
  }
  VideoReader full(deep), gray(deep, /*gray_only=*/true);
  for (int i = 0; i < 4; ++i) {
    cv::Mat a, b;
    ASSERT_TRUE(full.ReadGray(&a, cv::Size(64, 48)));
    ASSERT_TRUE(gray.ReadGray(&b, cv::Size(64, 48)));
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "frame " << i;
  }
  cv::Mat bgr, g;
  ASSERT_TRUE(gray.Seek(0));
  EXPECT_THROW(gray.Read(&bgr), std::logic_error);
  EXPECT_THROW(gray.ReadGrayAndBgr(&g, cv::Size(), &bgr, cv::Size()),
               std::logic_error);
}

TEST(VideoReader, GrayReducedTwiceSkipsTheDeblockingOfBFrames) {
  // The estimate's reads, averaged down, leave out H.264's deblocking
  // filter on B-frames: a sixth of the decode. Key frames must come out as a
  // full decode's; the B-frames differ, and the frames predicted from the
  // reference B-frames a little (until the next key frame), never by much.
  // Gray read whole, or by a colour reader, is a full decode's.
  const fs::path d = TempDir("deblock");
  const std::string h264 = (d / "noisy.mp4").string();
  // Coarse quantisation over noise: block edges the filter has work on.
  if (!Ffmpeg("-f lavfi -i testsrc2=size=160x120:rate=25,noise=alls=40:allf=t "
              "-frames:v 24 -c:v libx264 -bf 3 -g 12 -crf 40 -pix_fmt "
              "yuv420p " +
              h264))
    GTEST_SKIP() << "ffmpeg with lavfi and libx264 is not available";
  std::string types;
  if (FILE* p = popen(("ffprobe -v error -select_streams v -show_entries "
                       "frame=pict_type -of csv=p=0 " +
                       h264)
                          .c_str(),
                      "r")) {
    for (int c; (c = std::fgetc(p)) != EOF;)
      if (c == 'I' || c == 'P' || c == 'B') types += static_cast<char>(c);
    pclose(p);
  }
  if (types.size() != 24) GTEST_SKIP() << "ffprobe gave no frame types";
  ASSERT_NE(types.find('B'), std::string::npos) << types;
  const cv::Size half(80, 60);
  VideoReader full(h264), gray(h264, /*gray_only=*/true);
  VideoReader full_whole(h264), gray_whole(h264, /*gray_only=*/true);
  int b_frames_changed = 0;
  for (int i = 0; i < 24; ++i) {
    cv::Mat a, b, diff, a_whole, b_whole;
    ASSERT_TRUE(full.ReadGray(&a, half));
    ASSERT_TRUE(gray.ReadGray(&b, half));
    cv::absdiff(a, b, diff);
    if (types[i] == 'I') EXPECT_EQ(cv::countNonZero(diff), 0) << "frame " << i;
    if (types[i] == 'B') b_frames_changed += cv::countNonZero(diff) > 0;
    EXPECT_LE(cv::mean(diff)[0], 2.0) << "frame " << i << " " << types;
    ASSERT_TRUE(full_whole.ReadGray(&a_whole));
    ASSERT_TRUE(gray_whole.ReadGray(&b_whole));
    EXPECT_EQ(cv::norm(a_whole, b_whole, cv::NORM_INF), 0.0) << "frame " << i;
  }
  EXPECT_GT(b_frames_changed, 0) << types;
}

TEST(VideoReader, SaysWhetherItsFramesDecodeOnTheirOwn) {
  // Skipping frames saves their decoding only where each decodes alone.
  const fs::path d = TempDir("independent");
  const std::string mjpeg = NumberedMovie(d, 30);
  EXPECT_TRUE(VideoReader(mjpeg).frames_independent());
  const std::string h264 = (d / "long_gop.mp4").string();
  if (!Ffmpeg("-i " + mjpeg + " -c:v libx264 -g 10 -pix_fmt yuv420p " + h264))
    GTEST_SKIP() << "ffmpeg with libx264 is not available";
  EXPECT_FALSE(VideoReader(h264).frames_independent());
  for (int i = 0; i < 2; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "s_%03d.png", i + 1);
    cv::imwrite((d / name).string(), cv::Mat(24, 32, CV_8UC3, cv::Scalar(i)));
  }
  EXPECT_TRUE(VideoReader((d / "s_001.png").string()).frames_independent());
}

TEST(VideoReader, ReadsAnMp4FromItsHeaderAsFromAProbedMovie) {
  // A QuickTime/MP4 movie is opened from its header alone (no probing); one
  // whose header has no frame count (a fragmented MP4) is probed. Each must
  // give the frames, count and rate a probed container (Matroska) gives.
  const fs::path d = TempDir("header");
  const std::string src = NumberedMovie(d, 40);
  const std::string x264 = " -c:v libx264 -g 10 -bf 2 -pix_fmt yuv420p ";
  const std::string mkv = (d / "probed.mkv").string();
  const std::string mp4 = (d / "plain.mp4").string();
  const std::string frag = (d / "fragmented.mp4").string();
  if (!Ffmpeg("-i " + src + x264 + mkv) || !Ffmpeg("-i " + src + x264 + mp4) ||
      !Ffmpeg("-i " + src + x264 + "-movflags +frag_keyframe+empty_moov " +
              frag)) {
    GTEST_SKIP() << "ffmpeg with libx264 is not available";
  }
  VideoReader probed(mkv);
  for (const std::string& path : {mp4, frag}) {
    VideoReader r(path);
    EXPECT_EQ(r.CountFrames(), 40) << path;
    EXPECT_DOUBLE_EQ(r.fps(), probed.fps()) << path;
    EXPECT_EQ(r.width(), 32);
    EXPECT_EQ(r.height(), 24);
    cv::Mat f;
    for (int target : {0, 1, 17, 39, 5}) {
      ASSERT_TRUE(r.Seek(target)) << path << " " << target;
      ASSERT_TRUE(r.Read(&f)) << path << " " << target;
      EXPECT_EQ(r.last_frame().index, target) << path;
      EXPECT_NEAR(f.at<cv::Vec3b>(12, 16)[0], 2 * target, 4) << path;
    }
  }
}

TEST(VideoReader, SeeksNearToAKeyFrameAtOrBeforeTheTarget) {
  const fs::path d = TempDir("near");
  const std::string src = NumberedMovie(d, 120);
  const std::string path = (d / "gop30.mp4").string();
  if (!Ffmpeg("-i " + src +
              " -c:v libx264 -g 30 -keyint_min 30 -sc_threshold 0 " + path)) {
    GTEST_SKIP() << "ffmpeg with libx264 is not available";
  }
  VideoReader r(path);
  cv::Mat f;
  for (auto [target, key] : {std::pair{100, 90}, {10, 0}, {65, 60}}) {
    const int at = r.SeekNear(target);
    EXPECT_EQ(at, key) << target;
    ASSERT_TRUE(r.Read(&f)) << target;
    EXPECT_EQ(r.last_frame().index, at);
    EXPECT_NEAR(f.at<cv::Vec3b>(12, 16)[0], 2 * at, 4) << target;
  }
  // Reading on after a key frame read alone gives the frames after it.
  for (int next : {61, 62}) {
    ASSERT_TRUE(r.Read(&f));
    EXPECT_EQ(r.last_frame().index, next);
    EXPECT_NEAR(f.at<cv::Vec3b>(12, 16)[0], 2 * next, 4);
  }
  ASSERT_EQ(r.SeekNear(100), 90);
  ASSERT_TRUE(r.Seek(93));  // close ahead of a key frame read alone
  ASSERT_TRUE(r.Read(&f));
  EXPECT_NEAR(f.at<cv::Vec3b>(12, 16)[0], 2 * 93, 4);
  ASSERT_EQ(r.SeekNear(65), 60);
  ASSERT_TRUE(r.Read(&f));
  // The next frame is the next one, not its key frame.
  EXPECT_EQ(r.SeekNear(61), 61);
  // The container's index tells the key frames without moving the reader.
  EXPECT_EQ(r.KeyFrameAtOrBefore(100), 90);
  EXPECT_EQ(r.KeyFrameAtOrBefore(29), 0);
  EXPECT_EQ(r.position(), 61);
  // Close ahead across a key frame (from it, not through the frames
  // before it) and close ahead within a group: the exact frames.
  for (int target : {95, 99, 119}) {
    ASSERT_TRUE(r.Seek(target)) << target;
    ASSERT_TRUE(r.Read(&f)) << target;
    EXPECT_EQ(r.last_frame().index, target);
    EXPECT_NEAR(f.at<cv::Vec3b>(12, 16)[0], 2 * target, 4) << target;
  }
  EXPECT_EQ(r.SeekNear(120), -1);
}

TEST(VideoReader, AResolutionChangeMidStreamIsReportedPerFrame) {
  const fs::path d = TempDir("res");
  const std::string a = (d / "a.ts").string(), b = (d / "b.ts").string();
  if (!Ffmpeg("-f lavfi -i color=c=red:s=64x48:r=10:d=0.5 -c:v mpeg2video " +
              a) ||
      !Ffmpeg("-f lavfi -i color=c=blue:s=80x64:r=10:d=0.5 -c:v mpeg2video " +
              b)) {
    GTEST_SKIP() << "no ffmpeg command to make the clip";
  }
  // MPEG-TS streams concatenate byte for byte; the decoder changes size.
  const std::string joined = (d / "joined.ts").string();
  {
    std::ofstream out(joined, std::ios::binary);
    out << std::ifstream(a, std::ios::binary).rdbuf()
        << std::ifstream(b, std::ios::binary).rdbuf();
  }
  VideoReader r(joined);
  EXPECT_EQ(r.width(), 64);
  cv::Mat f;
  int ok = 0, changed = 0;
  while (r.Read(&f)) {
    if (r.last_frame().status == FrameStatus::kOk) {
      ++ok;
      EXPECT_EQ(f.cols, 64);
    } else if (r.last_frame().status == FrameStatus::kSizeChanged) {
      ++changed;
      EXPECT_TRUE(f.empty());
      EXPECT_EQ(r.last_frame().width, 80);
    }
  }
  // 5 + 5 frames; the decoder may drop one where the two streams meet.
  EXPECT_GE(ok, 4);
  EXPECT_GE(changed, 4);
  EXPECT_GE(ok + changed, 9);
  EXPECT_LE(ok + changed, 10);
}

TEST(VideoReader, CountsTheFramesOfAMovieWithoutACountInItsHeader) {
  const fs::path d = TempDir("count");
  const std::string path = (d / "clip.mkv").string();
  if (!Ffmpeg("-f lavfi -i testsrc=s=32x24:r=10:d=1.3 -c:v mjpeg " + path)) {
    GTEST_SKIP() << "no ffmpeg command to make the clip";
  }
  VideoReader r(path);
  EXPECT_FALSE(r.num_frames_exact());
  EXPECT_EQ(r.CountFrames(), 13);
  EXPECT_TRUE(r.num_frames_exact());
  cv::Mat f;
  int n = 0;
  while (r.Read(&f)) n += !f.empty();
  EXPECT_EQ(n, 13);
}

TEST(VideoReader, MissingOrUndecodableFilesThrow) {
  EXPECT_THROW(VideoReader("/nonexistent/clip.mp4"), std::invalid_argument);
  const fs::path d = TempDir("bad");
  std::ofstream(d / "clip.mp4") << "garbage";
  EXPECT_THROW(VideoReader((d / "clip.mp4").string()), std::invalid_argument);
}

// A tiny PNG whose header claims `width` x `height` pixels (its one row of
// data is all it has); the header's CRC is kept valid.
std::string PngClaiming(const fs::path& d, uint32_t width, uint32_t height) {
  std::vector<uchar> png;
  cv::imencode(".png", cv::Mat(1, 1, CV_8UC3, cv::Scalar(1, 2, 3)), png);
  auto put32 = [&](size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) png[at + i] = (v >> (24 - 8 * i)) & 0xff;
  };
  put32(16, width);  // IHDR: 8 signature + 4 length + 4 type
  put32(20, height);
  uint32_t crc = 0xffffffffu;  // over the chunk type and its 13 data bytes
  for (size_t i = 12; i < 12 + 4 + 13; ++i) {
    crc ^= png[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & -(crc & 1));
  }
  put32(29, ~crc);
  const std::string path = (d / "huge.png").string();
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()), png.size());
  return path;
}

// A 70-byte file must not make the reader allocate gigabytes (FFmpeg's own
// limit is ~268 million pixels; this header asks for 768 MB per frame).
TEST(VideoReader, RefusesFramesTooLargeToBeFootage) {
  const fs::path d = TempDir("huge");
  const std::string huge = PngClaiming(d, 16000, 16000);
  rusage before{}, after{};
  getrusage(RUSAGE_SELF, &before);
  EXPECT_THROW(VideoReader{huge}, std::invalid_argument);
  getrusage(RUSAGE_SELF, &after);
  // ru_maxrss (kB) is the peak so far: it rises if the frame was allocated.
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 200 * 1024);
  // The same file at its true size opens (the patching keeps it valid).
  EXPECT_EQ(VideoReader(PngClaiming(d, 1, 1)).width(), 1);
}

TEST(VideoReader, ANumberTooLongForAnIntStillReads) {
  const fs::path d = TempDir("long");
  const std::string path = (d / "f_123456789012.png").string();
  cv::imwrite(path, Frame(1));
  VideoReader r(path);  // threw std::out_of_range from std::stoi
  EXPECT_EQ(r.num_frames(), 1);
  cv::Mat f;
  ASSERT_TRUE(r.Read(&f));
  EXPECT_EQ(r.last_frame().status, FrameStatus::kOk);
}

TEST(VideoReader, LinearGrayUndoesGamma) {
  cv::Mat img(1, 1, CV_8UC3, cv::Scalar(128, 128, 128));
  const cv::Mat g = ToLinearGray(img, 2.2);
  EXPECT_NEAR(g.at<float>(0, 0), std::pow(128 / 255.0, 2.2), 1e-4);
  EXPECT_NEAR(ToLinearGray(img, 1.0).at<float>(0, 0), 128 / 255.0, 1e-6);
}

// Reduced pixel (i, j) stands for full-size pixel (i * stride, j * stride):
// its block is centred there (a point sample would see only that pixel),
// averaged after the table, with the border repeated.
TEST(VideoReader, CentredBlockMeansAverageAroundTheSampledPixel) {
  const cv::Mat squared = [] {
    cv::Mat t(1, 256, CV_32F);
    for (int v = 0; v < 256; ++v) t.at<float>(0, v) = float(v * v);
    return t;
  }();
  constexpr int kStride = 8;
  cv::Mat img(37, 61, CV_8UC3, cv::Scalar(0, 0, 0));  // not multiples of 8
  // Beside full-size pixel (16, 24), inside the block of reduced (2, 3) but
  // not its sampled pixel; one 200 in its 64.
  img.at<cv::Vec3b>(2 * kStride + 3, 3 * kStride - 4) = cv::Vec3b(200, 10, 0);
  const cv::Mat out = CentredBlockMeans(img, kStride, squared);
  ASSERT_EQ(out.type(), CV_32FC3);
  EXPECT_EQ(out.rows, (37 + kStride - 1) / kStride);
  EXPECT_EQ(out.cols, (61 + kStride - 1) / kStride);
  const cv::Vec3f v = out.at<cv::Vec3f>(2, 3);
  EXPECT_NEAR(v[0], 200.f * 200.f / 64.f, 1e-2);  // the mean of the squares
  EXPECT_NEAR(v[1], 100.f / 64.f, 1e-3);
  EXPECT_EQ(cv::countNonZero(out.reshape(1) != 0.f), 2);
  // A uniform frame stays uniform to its edges (the border repeated).
  const cv::Mat flat = CentredBlockMeans(
      cv::Mat(37, 61, CV_8UC3, cv::Scalar(3, 3, 3)), kStride, squared);
  double lo = 0, hi = 0;
  cv::minMaxLoc(flat.reshape(1), &lo, &hi);
  EXPECT_FLOAT_EQ(lo, 9.f);
  EXPECT_FLOAT_EQ(hi, 9.f);
  // Stride 1 is the table alone.
  EXPECT_FLOAT_EQ(CentredBlockMeans(img, 1, squared)
                      .at<cv::Vec3f>(2 * kStride + 3, 3 * kStride - 4)[0],
                  40000.f);
  EXPECT_THROW(CentredBlockMeans(img, 0, squared), std::invalid_argument);
}

}  // namespace
}  // namespace sunlapse
