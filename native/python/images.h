// numpy images seen as cv::Mat without copies, and cv::Mat handed to
// numpy without copies, for the bindings of every stage that takes or gives
// frames.
#pragma once

#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "arrays.h"

namespace sunlapse::python {

// A cv::Mat viewing (not copying) a checked numpy image: float32 (H,W), or
// (H,W,3) too with `colour`.
inline cv::Mat FloatView(const py::array& a, const char* name,
                         bool colour = false) {
  const bool three = colour && a.ndim() == 3;
  const float* data = three ? CheckArray<float>(a, name, {-1, -1, 3})
                            : CheckArray<float>(a, name, {-1, -1});
  return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)),
                 CV_32FC(three ? 3 : 1), const_cast<float*>(data));
}

// The same for a uint8 (H,W) mask.
inline cv::Mat MaskView(const py::array& a, const char* name) {
  const uint8_t* data = CheckArray<uint8_t>(a, name, {-1, -1});
  return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)),
                 CV_8UC1, const_cast<uint8_t*>(data));
}

// A float32 (H,W) frame, or an empty Mat for None (a frame that could not
// be decoded).
inline cv::Mat GrayArg(const py::object& frame) {
  if (frame.is_none()) return {};
  return FloatView(frame.cast<py::array>(), "frame");
}

// A numpy array owning `m` (no copy): the Mat's buffer lives as long as the
// array.
inline py::array MatAsArray(cv::Mat m) {
  if (!m.isContinuous()) m = m.clone();
  auto* held = new cv::Mat(std::move(m));
  py::capsule owner(held, [](void* p) { delete static_cast<cv::Mat*>(p); });
  std::vector<py::ssize_t> shape{held->rows, held->cols};
  if (held->channels() > 1) shape.push_back(held->channels());
  if (held->depth() == CV_32F)
    return py::array_t<float>(shape, reinterpret_cast<float*>(held->data),
                              owner);
  return py::array_t<uint8_t>(shape, held->data, owner);
}

}  // namespace sunlapse::python
