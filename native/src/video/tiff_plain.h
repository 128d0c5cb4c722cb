// Uncompressed 16-bit RGB TIFF stills (a raw converter's export) read
// straight from the file into a buffer kept from one still to the next.
// FFmpeg's TIFF decoder opens a decoder per still and fills a fresh 50 MB
// picture each time (4K, 16 bits): on a virtual machine its first writes
// cost more than the reading (ffmpeg: 2.8 s user, 4.4 s system for 20
// stills). Internal to the video stage: VideoReader uses it for a
// sequence's TIFF images and falls back to FFmpeg for anything it refuses
// (compressed, tiled, planar, 8-bit, gray, another orientation, BigTIFF).
#pragma once

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace sunlapse {

class PlainTiff {
 public:
  // Empty when `path` is a baseline TIFF this reads (uncompressed, in
  // strips, 16-bit unsigned RGB or RGBA, chunky, top-left, no more than
  // max_pixels), else why not. Reads the header and the first directory.
  std::string Open(const std::string& path, int64_t max_pixels);
  int width() const { return width_; }
  int height() const { return height_; }
  // The opened still as CV_16UC3 (RGB) or CV_16UC4 (RGBA) in native byte
  // order, in the kept buffer (valid until the next Read). False when the
  // file ends before its strips do.
  bool Read(cv::Mat* rgb);

 private:
  std::ifstream in_;
  bool big_endian_ = false;
  int width_ = 0, height_ = 0, channels_ = 0, rows_per_strip_ = 0;
  std::vector<uint64_t> strip_offsets_, strip_bytes_;
  std::vector<uint16_t> buffer_;
};

}  // namespace sunlapse
