// JPEG stills decoded for the size the estimate reads them at (issue 28),
// with libjpeg-turbo: the luma alone (no chroma transform, upsampling or
// colour conversion), at 1/2, 1/4 or 1/8 where the reduction's geometry
// allows (the scaled inverse DCT, and no full-size picture to reduce). A
// 24 MP still of a camera's fine quality: FFmpeg 130 ms, TurboJPEG's luma
// 87 ms whole, 68 ms at an eighth (its entropy decoding, which no scaling
// saves). Internal to the video stage: VideoReader uses it for a
// sequence's JPEG images and falls back to FFmpeg for anything it refuses.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace sunlapse {

// The shrink (1, 2, 4 or 8: the DCT scalings TurboJPEG offers) to decode
// an image of `full` size at for an area average down to `size`: the
// largest that makes every output pixel cover whole shrink x shrink blocks
// (full = size * k * shrink on both axes). libjpeg's scaled inverse DCT
// gives each block's mean (jidctred.c: the means of the whole transform's
// outputs), so AreaReduced from that picture averages exactly the camera
// pixels it averages from the full one. A size that divides the frame by
// no whole number (6530 / 816) keeps 1: an output pixel's border then cuts
// through blocks, whose pixels a block's mean cannot tell apart. 1 too for
// an empty size and for tiny images (nothing to gain, and below 8 pixels a
// side TurboJPEG could pick another scaling than the one meant).
int JpegShrinkFor(cv::Size full, cv::Size size);

// 8-bit BGR of `size` from a JPEG's Y, Cb and Cr planes (cb, cr empty for
// a gray JPEG), each area-averaged to `size` first and then converted as
// JPEG's YCbCr (cv::COLOR_YCrCb2BGR): averaging before the linear
// conversion differs only where a channel clips. Planes are stretched over
// `size` as they come (subsampled chroma half a camera pixel off at an odd
// side; scaled planes' last block part padding): colour for a background,
// not a measurement.
cv::Mat BgrFromPlanes(const cv::Mat& y, const cv::Mat& cb, const cv::Mat& cr,
                      cv::Size size);

// One TurboJPEG decompressor and the file it holds (a reader's own: the
// handle is not shared between threads). Its buffers are reused, so a
// sequence's memory stays flat and a 24 MP still costs no 24 MB of fresh
// pages each.
class ScaledJpeg {
 public:
  ScaledJpeg();
  ~ScaledJpeg();
  ScaledJpeg(const ScaledJpeg&) = delete;
  ScaledJpeg& operator=(const ScaledJpeg&) = delete;

  // Reads `path` and its header. Empty when it can be decoded here, else
  // why not: the caller then decodes it another way (not a JPEG, CMYK or
  // YCCK, a header TurboJPEG refuses, larger than `max_pixels`).
  std::string Open(const std::string& path, int64_t max_pixels);
  int width() const { return width_; }
  int height() const { return height_; }

  // The opened image's luma at 1/shrink (1, 2, 4 or 8), its chroma neither
  // transformed nor converted; valid until the next decode. Null on any
  // error or warning (a corrupt or truncated file: TurboJPEG stops at the
  // first).
  const cv::Mat* Gray(int shrink);
  // Its Y, Cb and Cr planes at 1/shrink as decoded (chroma at its own
  // subsampling; a gray JPEG: Y alone, cb and cr empty): gray and colour
  // from one decode. Valid until the next decode; false as Gray().
  bool Planes(int shrink, cv::Mat* y, cv::Mat* cb, cv::Mat* cr);

 private:
  // TurboJPEG's scaling for `shrink` and the scaled size; false when it
  // offers none such or nothing is open.
  bool Scaled(int shrink, int* w, int* h) const;

  void* handle_ = nullptr;  // tjhandle
  std::vector<unsigned char> data_;
  int width_ = 0, height_ = 0, subsamp_ = 0;
  cv::Mat planes_[3];  // Y, Cb, Cr (reused)
};

}  // namespace sunlapse
