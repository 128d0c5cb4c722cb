#include "jpeg_scaled.h"

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <turbojpeg.h>
#include <opencv2/imgproc.hpp>

#include "sunlapse/video/video_reader.h"

namespace sunlapse {

int JpegShrinkFor(cv::Size full, cv::Size size) {
  if (size.empty() || full.width < 64 || full.height < 64 ||
      full.width % size.width != 0 || full.height % size.height != 0)
    return 1;
  const int kx = full.width / size.width, ky = full.height / size.height;
  int shrink = 1;
  while (shrink < 8 && kx % (shrink * 2) == 0 && ky % (shrink * 2) == 0)
    shrink *= 2;
  return shrink;
}

ScaledJpeg::ScaledJpeg() : handle_(tjInitDecompress()) {}

ScaledJpeg::~ScaledJpeg() {
  if (handle_ != nullptr) tjDestroy(static_cast<tjhandle>(handle_));
}

std::string ScaledJpeg::Open(const std::string& path, int64_t max_pixels) {
  width_ = height_ = 0;
  if (handle_ == nullptr) return "no TurboJPEG decompressor";
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"),
                                             &std::fclose);
  if (!file) return "cannot open the file";
  if (std::fseek(file.get(), 0, SEEK_END) != 0) return "cannot read the file";
  const long size = std::ftell(file.get());
  // A JPEG of 8192 x 8192 pixels is far below a gigabyte.
  if (size <= 0 || size > (long{1} << 30)) return "not a JPEG file's size";
  std::rewind(file.get());
  data_.resize(static_cast<size_t>(size));
  if (std::fread(data_.data(), 1, data_.size(), file.get()) != data_.size())
    return "cannot read the file";
  int w = 0, h = 0, subsamp = 0, colorspace = 0;
  if (tjDecompressHeader3(static_cast<tjhandle>(handle_), data_.data(),
                          data_.size(), &w, &h, &subsamp, &colorspace) != 0)
    return tjGetErrorStr2(static_cast<tjhandle>(handle_));
  // Four-channel JPEGs have no luma to take as gray.
  if (colorspace == TJCS_CMYK || colorspace == TJCS_YCCK) return "a CMYK JPEG";
  if (w <= 0 || h <= 0 || static_cast<int64_t>(w) * h > max_pixels)
    return "too large a JPEG";
  width_ = w;
  height_ = h;
  subsamp_ = subsamp;
  return {};
}

bool ScaledJpeg::Scaled(int shrink, int* w, int* h) const {
  if (width_ == 0) return false;
  // The scaling as TurboJPEG offers it (1/1, 1/2, 1/4, 1/8 in every build).
  int n = 0;
  const tjscalingfactor* factors = tjGetScalingFactors(&n);
  bool offered = false;
  for (int i = 0; factors != nullptr && i < n; ++i)
    offered = offered || (factors[i].num == 1 && factors[i].denom == shrink);
  if (!offered) return false;
  const tjscalingfactor factor{1, shrink};
  *w = TJSCALED(width_, factor);
  *h = TJSCALED(height_, factor);
  return true;
}

const cv::Mat* ScaledJpeg::Gray(int shrink) {
  int w = 0, h = 0;
  if (!Scaled(shrink, &w, &h)) return nullptr;
  cv::Mat& y = planes_[0];
  y.create(h, w, CV_8UC1);
  // A warning (corrupt data, a truncated file) stops the decode: such an
  // image is left to the other decoder, which reports it as it always has.
  if (tjDecompress2(static_cast<tjhandle>(handle_), data_.data(), data_.size(),
                    y.data, w, static_cast<int>(y.step[0]), h, TJPF_GRAY,
                    TJFLAG_STOPONWARNING) != 0)
    return nullptr;
  return &y;
}

bool ScaledJpeg::Planes(int shrink, cv::Mat* y, cv::Mat* cb, cv::Mat* cr) {
  int w = 0, h = 0;
  if (!Scaled(shrink, &w, &h)) return false;
  const int count = subsamp_ == TJSAMP_GRAY ? 1 : 3;
  unsigned char* dst[3] = {nullptr, nullptr, nullptr};
  int strides[3] = {0, 0, 0};
  for (int c = 0; c < count; ++c) {
    const int pw = tjPlaneWidth(c, w, subsamp_),
              ph = tjPlaneHeight(c, h, subsamp_);
    if (pw <= 0 || ph <= 0) return false;
    planes_[c].create(ph, pw, CV_8UC1);
    dst[c] = planes_[c].data;
    strides[c] = static_cast<int>(planes_[c].step[0]);
  }
  if (tjDecompressToYUVPlanes(static_cast<tjhandle>(handle_), data_.data(),
                              data_.size(), dst, w, strides, h,
                              TJFLAG_STOPONWARNING) != 0)
    return false;
  // TurboJPEG pads the luma plane to whole chroma samples: cut to the image.
  *y = planes_[0](cv::Rect(0, 0, w, h));
  *cb = count == 3 ? planes_[1] : cv::Mat();
  *cr = count == 3 ? planes_[2] : cv::Mat();
  return true;
}

cv::Mat BgrFromPlanes(const cv::Mat& y, const cv::Mat& cb, const cv::Mat& cr,
                      cv::Size size) {
  cv::Mat bgr;
  if (cb.empty()) {
    cv::cvtColor(AreaReduced(y, size), bgr, cv::COLOR_GRAY2BGR);
    return bgr;
  }
  cv::Mat ycrcb;
  cv::merge(std::vector<cv::Mat>{AreaReduced(y, size), AreaReduced(cr, size),
                                 AreaReduced(cb, size)},
            ycrcb);
  cv::cvtColor(ycrcb, bgr, cv::COLOR_YCrCb2BGR);
  return bgr;
}

}  // namespace sunlapse
