#include "jpeg_scaled.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <turbojpeg.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "sunlapse/video/frame_stream.h"
#include "sunlapse/video/video_reader.h"
#include "temp_dir.h"

namespace sunlapse {
namespace {
namespace fs = std::filesystem;

using testing::TempDir;

// Grain over a colour gradient, as a camera's still has.
cv::Mat Still(int width, int height, int seed) {
  cv::Mat img(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      img.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uchar>(40 + 150 * x / width),
                    static_cast<uchar>(60 + 120 * y / height),
                    static_cast<uchar>(200 - 120 * (x + y) / (width + height)));
  cv::Mat grain(height, width, CV_8UC3);
  cv::theRNG().state = seed;
  cv::randu(grain, 0, 30);
  return img + grain;
}

// Stripes 13 pixels wide and 11 high (no multiple of any block), two
// levels of gray: every output pixel that straddles a border changes by
// an eighth of the step or more when the geometry moves one pixel.
cv::Mat Stripes(int width, int height) {
  cv::Mat img(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      img.at<cv::Vec3b>(y, x) =
          cv::Vec3b::all(((x / 13) + (y / 11)) % 2 ? 190 : 60);
  return img;
}

// The first file of a two-image sequence of `img`.
std::string Jpegs(const fs::path& d, const std::string& name,
                  const cv::Mat& img,
                  std::vector<int> params = {cv::IMWRITE_JPEG_QUALITY, 92}) {
  for (int i = 1; i <= 2; ++i)
    cv::imwrite((d / (name + "_" + std::to_string(i) + ".jpg")).string(), img,
                params);
  return (d / (name + "_1.jpg")).string();
}

// What the reader gave before TurboJPEG: FFmpeg's whole picture (its
// luma), reduced by AreaReduced. ReadGray at the decoded size decodes whole.
cv::Mat WholeThenReduced(const std::string& path, cv::Size size) {
  VideoReader r(path);
  cv::Mat full;
  EXPECT_TRUE(r.ReadGray(&full));
  EXPECT_EQ(r.last_frame().status, FrameStatus::kOk);
  return AreaReduced(full, size);
}

cv::Mat ScaledRead(const std::string& path, cv::Size size) {
  VideoReader r(path);
  cv::Mat gray;
  EXPECT_TRUE(r.ReadGray(&gray, size));
  EXPECT_EQ(r.last_frame().status, FrameStatus::kOk);
  EXPECT_EQ(r.last_frame().width, r.width());
  return gray;
}

double Worst(const cv::Mat& a, const cv::Mat& b) {
  return cv::norm(a, b, cv::NORM_INF);
}

double Mean(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  return cv::mean(diff)[0];
}

TEST(JpegShrinkFor, EveryOutputPixelCoversWholeBlocks) {
  // The estimate's sizes: the clip divided by a power of two, rounded down.
  EXPECT_EQ(JpegShrinkFor({6000, 4000}, {750, 500}), 8);
  EXPECT_EQ(JpegShrinkFor({6000, 4000}, {375, 250}), 8);  // an eighth at most
  EXPECT_EQ(JpegShrinkFor({4000, 3000}, {1000, 750}), 4);
  EXPECT_EQ(JpegShrinkFor({650, 490}, {325, 245}), 2);
  EXPECT_EQ(JpegShrinkFor({640, 480}, {80, 60}), 8);
  // An output pixel of 8.0025 camera pixels (6530 / 816) cuts blocks.
  EXPECT_EQ(JpegShrinkFor({6530, 3674}, {816, 459}), 1);
  EXPECT_EQ(JpegShrinkFor({650, 490}, {162, 122}), 1);
  EXPECT_EQ(JpegShrinkFor({1001, 777}, {500, 388}), 1);
  // Both axes: 6 camera pixels wide, 4 high.
  EXPECT_EQ(JpegShrinkFor({960, 480}, {160, 120}), 2);
  // Nothing for the full size, none asked, tiny images.
  EXPECT_EQ(JpegShrinkFor({640, 480}, {640, 480}), 1);
  EXPECT_EQ(JpegShrinkFor({640, 480}, {}), 1);
  EXPECT_EQ(JpegShrinkFor({40, 32}, {5, 4}), 1);
}

// The estimate's sizes for a clip: W / f x H / f, rounded down (whole_clip.py).
cv::Size Working(cv::Size full, int factor) {
  return {full.width / factor, full.height / factor};
}

// TurboJPEG's luma of `path` at JpegShrinkFor's scaling, area-reduced.
cv::Mat TurboReduced(const std::string& path, cv::Size size, int* shrink) {
  ScaledJpeg jpeg;
  EXPECT_EQ(jpeg.Open(path, VideoReader::kMaxFramePixels), "");
  *shrink = JpegShrinkFor({jpeg.width(), jpeg.height()}, size);
  const cv::Mat* gray = jpeg.Gray(*shrink);
  EXPECT_NE(gray, nullptr);
  return gray == nullptr ? cv::Mat() : AreaReduced(*gray, size).clone();
}

// The sizes and factors of the comparisons, and the scaling each must use.
struct Case {
  cv::Size full;
  int factor, shrink;
};
const Case kCases[] = {
    {{640, 480}, 2, 2},  {{640, 480}, 4, 4},  {{640, 480}, 8, 8},
    {{640, 480}, 16, 8}, {{650, 490}, 2, 2},  {{650, 490}, 4, 1},
    {{650, 490}, 8, 1},  {{1001, 777}, 2, 1}, {{1001, 777}, 4, 1},
    {{1000, 776}, 8, 8}, {{1000, 776}, 4, 4}};

TEST(ScaledJpeg, IsTheWholeDecodeAreaReducedWithinJpegRounding) {
  // libjpeg's 1/2, 1/4 and 1/8 inverse DCTs give each block's mean of the
  // whole transform's outputs before rounding to 8 bits (jidctred.c), and
  // its whole IDCT rounds otherwise than FFmpeg's: a level or two apart,
  // on sides that are and are not multiples of the blocks.
  const fs::path d = TempDir("jpeg_within");
  for (const Case& c : kCases) {
    const std::string path = Jpegs(d, "s" + std::to_string(c.full.width),
                                   Still(c.full.width, c.full.height, 7));
    const cv::Size size = Working(c.full, c.factor);
    const cv::Mat scaled = ScaledRead(path, size);
    const cv::Mat expected = WholeThenReduced(path, size);
    ASSERT_EQ(scaled.size(), size);
    EXPECT_LE(Worst(scaled, expected), 2.0) << c.full << " / " << c.factor;
    EXPECT_LT(Mean(scaled, expected), 0.6) << c.full << " / " << c.factor;
    // The reader's read is TurboJPEG's at the scaling meant.
    int shrink = 0;
    EXPECT_EQ(Worst(scaled, TurboReduced(path, size, &shrink)), 0.0);
    EXPECT_EQ(shrink, c.shrink) << c.full << " / " << c.factor;
  }
}

TEST(ScaledJpeg, KeepsTheGeometryToThePixel) {
  // Stripes that are no multiple of a block: the scaled read must match
  // the whole decode reduced, and the same reduced one pixel off must not.
  const fs::path d = TempDir("jpeg_geometry");
  for (const Case& c : kCases) {
    const std::string path = Jpegs(d, "g" + std::to_string(c.full.width),
                                   Stripes(c.full.width, c.full.height),
                                   {cv::IMWRITE_JPEG_QUALITY, 98});
    VideoReader whole(path);
    cv::Mat full_gray;
    ASSERT_TRUE(whole.ReadGray(&full_gray));
    const cv::Size size = Working(c.full, c.factor);
    const cv::Mat scaled = ScaledRead(path, size);
    const double tolerance = 3.0;
    EXPECT_LE(Worst(scaled, AreaReduced(full_gray, size)), tolerance)
        << c.full << " / " << c.factor;
    // One camera pixel right, and one down: an eighth of the stripes' step
    // or more on every output pixel over a border (at a sixteenth, two
    // borders in one output pixel can cancel).
    if (c.factor > 8) continue;
    for (const cv::Point shift : {cv::Point(1, 0), cv::Point(0, 1)}) {
      cv::Mat moved;
      const cv::Mat m =
          (cv::Mat_<double>(2, 3) << 1, 0, shift.x, 0, 1, shift.y);
      cv::warpAffine(full_gray, moved, m, full_gray.size(), cv::INTER_NEAREST,
                     cv::BORDER_REPLICATE);
      EXPECT_GT(Worst(scaled, AreaReduced(moved, size)), 3 * tolerance)
          << c.full << " / " << c.factor << " shift " << shift;
    }
  }
}

TEST(ScaledJpeg, BlockMeansCannotKeepAnOutputBorderInsideABlock) {
  // Why JpegShrinkFor decodes 6530 x 3674 whole for 816 x 459: from the
  // eighth-size picture, whatever the weights, an output pixel whose
  // border cuts a block gets that block's mean, not its part's.
  const fs::path d = TempDir("jpeg_cut");
  const std::string path =
      Jpegs(d, "c", Stripes(650, 490), {cv::IMWRITE_JPEG_QUALITY, 98});
  ScaledJpeg jpeg;
  ASSERT_EQ(jpeg.Open(path, VideoReader::kMaxFramePixels), "");
  ASSERT_NE(jpeg.Gray(4), nullptr);
  const cv::Mat quarter = jpeg.Gray(4)->clone();
  ASSERT_NE(jpeg.Gray(1), nullptr);
  const cv::Mat whole = jpeg.Gray(1)->clone();
  EXPECT_EQ(quarter.size(),
            cv::Size(163, 123));  // ceil(650 / 4) x ceil(490 / 4)
  const cv::Size size(162, 122);  // 4.012 camera pixels an output pixel
  cv::Mat stretched;
  cv::resize(quarter(cv::Rect(0, 0, 162, 122)), stretched, size, 0, 0,
             cv::INTER_AREA);
  EXPECT_GT(Worst(stretched, AreaReduced(whole, size)), 20.0);
}

TEST(ScaledJpeg, GrayIsTheLumaFfmpegGivesAndBgrToGrayWeighs) {
  // JPEG's Y is 0.299 R + 0.587 G + 0.114 B (full range): what FFmpeg's
  // luma plane gave as gray, and what cv::COLOR_BGR2GRAY makes of the
  // colour FFmpeg decodes.
  const fs::path d = TempDir("jpeg_luma");
  const std::string path = Jpegs(d, "y", Still(320, 240, 3));
  ScaledJpeg jpeg;
  ASSERT_EQ(jpeg.Open(path, VideoReader::kMaxFramePixels), "");
  ASSERT_NE(jpeg.Gray(1), nullptr);
  const cv::Mat y = jpeg.Gray(1)->clone();
  VideoReader gray_reader(path), bgr_reader(path);
  cv::Mat ffmpeg_gray, ffmpeg_bgr, from_bgr;
  ASSERT_TRUE(gray_reader.ReadGray(&ffmpeg_gray));
  EXPECT_LE(Worst(y, ffmpeg_gray), 1.0);
  ASSERT_TRUE(bgr_reader.Read(&ffmpeg_bgr));
  cv::cvtColor(ffmpeg_bgr, from_bgr, cv::COLOR_BGR2GRAY);
  // swscale's bicubic chroma and fixed-point conversion round on top.
  EXPECT_LE(Worst(y, from_bgr), 3.0);
  EXPECT_LT(Mean(y, from_bgr), 1.0);
  // The planes' Y is the same luma, at every scaling.
  for (int shrink : {1, 2, 4, 8}) {
    cv::Mat py, cb, cr;
    ASSERT_TRUE(jpeg.Planes(shrink, &py, &cb, &cr));
    const cv::Mat planes_y = py.clone();
    ASSERT_NE(jpeg.Gray(shrink), nullptr);
    EXPECT_EQ(Worst(planes_y, *jpeg.Gray(shrink)), 0.0) << shrink;
    EXPECT_EQ(cb.size(), cv::Size((planes_y.cols + 1) / 2,
                                  (planes_y.rows + 1) / 2));  // 4:2:0
  }
  // Odd sides: the luma plane, padded to whole chroma samples, is cut.
  const std::string odd = Jpegs(d, "odd", Still(1001, 777, 3));
  ASSERT_EQ(jpeg.Open(odd, VideoReader::kMaxFramePixels), "");
  for (int shrink : {1, 2}) {
    cv::Mat py, cb, cr;
    ASSERT_TRUE(jpeg.Planes(shrink, &py, &cb, &cr));
    const cv::Mat planes_y = py.clone();
    ASSERT_NE(jpeg.Gray(shrink), nullptr);
    ASSERT_EQ(planes_y.size(), jpeg.Gray(shrink)->size());
    EXPECT_EQ(Worst(planes_y, *jpeg.Gray(shrink)), 0.0) << shrink;
  }
}

// A CMYK JPEG (Adobe's, as print workflows write them), made by TurboJPEG.
std::string CmykJpeg(const fs::path& d, int width, int height) {
  std::vector<unsigned char> cmyk(static_cast<size_t>(width) * height * 4);
  for (size_t i = 0; i < cmyk.size(); ++i)
    cmyk[i] = static_cast<uchar>(i % 251);
  tjhandle h = tjInitCompress();
  unsigned char* out = nullptr;
  unsigned long size = 0;
  const int err = tjCompress2(h, cmyk.data(), width, 0, height, TJPF_CMYK, &out,
                              &size, TJSAMP_444, 90, 0);
  tjDestroy(h);
  EXPECT_EQ(err, 0);
  const std::string path = (d / "cmyk_1.jpg").string();
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(out),
             static_cast<std::streamsize>(size));
  tjFree(out);
  return path;
}

TEST(ScaledJpeg, RefusesWhatItShouldNotDecode) {
  const fs::path d = TempDir("jpeg_refuses");
  ScaledJpeg jpeg;
  EXPECT_EQ(jpeg.Gray(8), nullptr);  // nothing opened
  std::ofstream(d / "text.jpg") << "not a jpeg";
  EXPECT_NE(jpeg.Open((d / "text.jpg").string(), 1 << 26), "");
  EXPECT_NE(jpeg.Open((d / "missing.jpg").string(), 1 << 26), "");
  EXPECT_NE(jpeg.Open(CmykJpeg(d, 96, 80), 1 << 26), "");
  const std::string ok = Jpegs(d, "ok", Still(200, 100, 1));
  EXPECT_NE(jpeg.Open(ok, 200 * 100 - 1), "");  // larger than allowed
  ASSERT_EQ(jpeg.Open(ok, 200 * 100), "");
  EXPECT_EQ(jpeg.width(), 200);
  EXPECT_EQ(jpeg.Gray(3), nullptr);  // no such scaling
  ASSERT_NE(jpeg.Gray(8), nullptr);
  EXPECT_EQ(jpeg.Gray(8)->size(), cv::Size(25, 13));  // ceil(100 / 8)
}

// What the reader gives for frame 2 of `first`'s sequence at `size`.
struct Got {
  FrameStatus status;
  std::string message;
  cv::Mat gray;
};
Got SecondFrame(const std::string& first, cv::Size size) {
  VideoReader r(first);
  cv::Mat gray;
  EXPECT_TRUE(r.Seek(1));
  EXPECT_TRUE(r.ReadGray(&gray, size));
  return {r.last_frame().status, r.last_frame().message, gray};
}

TEST(ScaledJpeg, WhatTurboJpegRefusesReadsAsItAlwaysHas) {
  // Corrupt, truncated, CMYK, of another size: FFmpeg reads it whole, with
  // the same report (and picture) as before TurboJPEG; progressive JPEGs
  // TurboJPEG decodes itself.
  const fs::path d = TempDir("jpeg_fallback");
  const cv::Mat img = Still(650, 490, 5);
  const cv::Size size(162, 122);
  auto second = [&](const std::string& name) {
    return (d / (name + "_2.jpg")).string();
  };
  std::vector<std::string> firsts;
  {
    const std::string first = Jpegs(d, "garbage", img);
    std::ofstream(second("garbage"), std::ios::trunc) << "garbage";
    firsts.push_back(first);
  }
  {
    const std::string first = Jpegs(d, "cut", img);
    std::vector<char> bytes(fs::file_size(first));
    std::ifstream(first, std::ios::binary).read(bytes.data(), bytes.size());
    std::ofstream(second("cut"), std::ios::binary | std::ios::trunc)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size() / 2));
    firsts.push_back(first);
  }
  {
    const std::string first = Jpegs(d, "other", img);
    cv::imwrite(second("other"), Still(640, 480, 5));
    firsts.push_back(first);
  }
  for (const std::string& first : firsts) {
    const Got scaled = SecondFrame(first, size);
    const Got whole = SecondFrame(first, cv::Size(650, 490));
    EXPECT_EQ(scaled.status, whole.status) << first;
    EXPECT_EQ(scaled.message, whole.message) << first;
    EXPECT_EQ(scaled.gray.empty(), whole.gray.empty()) << first;
    if (!whole.gray.empty()) {  // FFmpeg conceals what it can
      EXPECT_EQ(Worst(scaled.gray, AreaReduced(whole.gray, size)), 0.0);
    }
  }
  // A CMYK sequence opens and reads through FFmpeg, whatever it makes of it.
  const std::string cmyk = CmykJpeg(d, 96, 80);
  fs::copy_file(cmyk, (d / "cmyk_2.jpg").string());
  const Got cmyk_scaled = SecondFrame(cmyk, cv::Size(12, 10));
  const Got cmyk_whole = SecondFrame(cmyk, cv::Size(96, 80));
  EXPECT_EQ(cmyk_scaled.status, cmyk_whole.status);
  EXPECT_EQ(cmyk_scaled.message, cmyk_whole.message);
  // Progressive: decoded scaled all the same.
  const std::string progressive =
      Jpegs(d, "prog", img,
            {cv::IMWRITE_JPEG_QUALITY, 92, cv::IMWRITE_JPEG_PROGRESSIVE, 1});
  EXPECT_LE(
      Worst(ScaledRead(progressive, size), WholeThenReduced(progressive, size)),
      8.0);
  // A first file that cannot be decoded still refuses the clip.
  std::ofstream(d / "bad_1.jpg") << "garbage";
  EXPECT_THROW(VideoReader((d / "bad_1.jpg").string()), std::invalid_argument);
}

TEST(ScaledJpeg, AMovieThenAScaledStillInOneProcess) {
  // FFmpeg's lowres corrupted the heap on exactly this order (a movie read
  // as gray, then a 650 x 490 JPEG decoded scaled); run under valgrind or
  // ASan to see it clean.
  const fs::path d = TempDir("jpeg_movie_then_still");
  const std::string movie = (d / "clip.avi").string();
  {
    cv::VideoWriter w(movie, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                      cv::Size(64, 48));
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 3; ++i) w.write(Still(64, 48, i));
  }
  VideoReader m(movie);
  cv::Mat gray;
  while (m.ReadGray(&gray, cv::Size(32, 24))) ASSERT_FALSE(gray.empty());
  const std::string still = Jpegs(d, "still", Still(650, 490, 9));
  for (const cv::Size size :
       {cv::Size(325, 245), cv::Size(162, 122), cv::Size(81, 61)}) {
    VideoReader r(still);
    cv::Mat bgr;
    while (r.ReadGrayAndBgr(&gray, size, &bgr, size)) {
      ASSERT_EQ(r.last_frame().status, FrameStatus::kOk);
      EXPECT_EQ(gray.size(), size);
      EXPECT_EQ(bgr.size(), size);
    }
  }
}

TEST(ScaledJpeg, ColourForTheNoteIsTheWholeColourReduced) {
  // The reference frames also come in colour (keep_bgr): two scaled
  // decodes, gray as ReadGray gives it, colour close to FFmpeg's reduced.
  const fs::path d = TempDir("jpeg_colour");
  const std::string path = Jpegs(d, "c", Still(1001, 777, 4));
  const cv::Size gray_size(250, 194), bgr_size(91, 71);  // the note's stride 11
  VideoReader both(path), bgr_reader(path);
  cv::Mat gray, bgr, whole_bgr;
  ASSERT_TRUE(both.ReadGrayAndBgr(&gray, gray_size, &bgr, bgr_size));
  EXPECT_EQ(Worst(gray, ScaledRead(path, gray_size)), 0.0);
  ASSERT_TRUE(bgr_reader.Read(&whole_bgr));
  ASSERT_EQ(bgr.size(), bgr_size);
  // libjpeg and swscale upsample the chroma differently.
  EXPECT_LT(cv::norm(bgr, AreaReduced(whole_bgr, bgr_size), cv::NORM_L1) /
                bgr.total() / 3,
            1.5);
  EXPECT_LE(Worst(bgr, AreaReduced(whole_bgr, bgr_size)), 12.0);
  // Sizes that divide the still: one decode at a quarter serves both.
  const std::string even = Jpegs(d, "e", Still(1000, 776, 2));
  VideoReader quarter(even), quarter_bgr(even);
  ASSERT_TRUE(quarter.ReadGrayAndBgr(&gray, {250, 194}, &bgr, {125, 97}));
  EXPECT_EQ(Worst(gray, ScaledRead(even, {250, 194})), 0.0);
  ASSERT_TRUE(quarter_bgr.Read(&whole_bgr));
  EXPECT_LE(Worst(bgr, AreaReduced(whole_bgr, {125, 97})), 12.0);
  // A colour size that cuts blocks beside a gray one that does not: the
  // planes at an eighth for both, the colour within its blocks' means.
  VideoReader eighth(even);
  ASSERT_TRUE(eighth.ReadGrayAndBgr(&gray, {125, 97}, &bgr, {91, 71}));
  EXPECT_EQ(Worst(gray, ScaledRead(even, {125, 97})), 0.0);
  cv::Mat blocks = AreaReduced(whole_bgr, {91, 71});
  EXPECT_LT(cv::norm(bgr, blocks, cv::NORM_L1) / bgr.total() / 3, 2.0);
  EXPECT_LE(Worst(bgr, blocks), 16.0);
  // A gray JPEG: its one plane, in three channels.
  cv::Mat one;
  cv::cvtColor(Still(400, 300, 1), one, cv::COLOR_BGR2GRAY);
  const std::string gray_jpeg = Jpegs(d, "gray", one);
  VideoReader gr(gray_jpeg);
  ASSERT_TRUE(gr.ReadGrayAndBgr(&gray, {100, 75}, &bgr, {50, 37}));
  ASSERT_EQ(gr.last_frame().status, FrameStatus::kOk);
  cv::Mat channels[3];
  cv::split(bgr, channels);
  EXPECT_EQ(Worst(channels[0], channels[2]), 0.0);
  // From the quarter-size plane (the gray's scaling): within its blocks.
  EXPECT_LE(Worst(channels[1], ScaledRead(gray_jpeg, {50, 37})), 3.0);
}

TEST(ScaledJpeg, StreamsInOrderOnEveryThreadWithTheSameReports) {
  // The stream's threads each decode scaled; a frame FFmpeg cannot decode
  // either reports as before.
  const fs::path d = TempDir("jpeg_stream");
  for (int i = 1; i <= 9; ++i)
    cv::imwrite((d / ("IMG_" + std::to_string(i) + ".jpg")).string(),
                Still(650, 490, i), {cv::IMWRITE_JPEG_QUALITY, 90});
  std::ofstream(d / "IMG_5.jpg", std::ios::trunc) << "garbage";
  const std::string first = (d / "IMG_1.jpg").string();
  FrameStreamOptions o;
  o.width = 162;
  o.height = 122;
  o.decode_threads = 3;
  o.queue_frames = 2;
  FrameStream s(first, {0, 1, 2, 3, 4, 5, 6, 7, 8}, o);
  StreamedFrame f;
  int k = 0;
  while (s.Next(&f)) {
    ASSERT_EQ(f.index, k);
    VideoReader r(first);
    cv::Mat gray;
    ASSERT_TRUE(r.Seek(k) && r.ReadGray(&gray, cv::Size(162, 122)));
    if (k == 4) {
      EXPECT_EQ(f.status, StreamedFrame::Status::kUnusable);
      EXPECT_EQ(f.message, r.last_frame().message);
      EXPECT_NE(f.message.find("cannot decode"), std::string::npos);
    } else {
      ASSERT_EQ(f.status, StreamedFrame::Status::kOk) << k;
      EXPECT_EQ(Worst(f.luma, gray), 0.0) << k;
    }
    ++k;
  }
  EXPECT_EQ(k, 9);
}

}  // namespace
}  // namespace sunlapse
