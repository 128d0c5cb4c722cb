#include "sunlapse/motion/view_warp.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <opencv2/imgproc.hpp>

#include "sunlapse/common/require.h"

namespace sunlapse {

void ViewWarpOptions::Check() const {
  Require(min_seen_share >= 0.0 && min_seen_share <= 1.0,
          "min_seen_share must be within [0, 1]");
  Require(hidden_share > 0.0 && hidden_share < 0.5,
          "hidden_share must be within (0, 0.5)");
}

struct ViewWarp::Impl {
  Impl(const Scene& s, const Camera& c, const ViewWarpOptions& o)
      : scene(s), reference(c), options(o) {}
  const Scene& scene;
  Camera reference;
  ViewWarpOptions options;
  // The reference pixels that see the model (row-major index) and the
  // surface point each sees.
  std::vector<int> pixel;
  std::vector<Eigen::Vector3f> point;
};

ViewWarp::ViewWarp(const Scene& scene, const Camera& reference,
                   const ViewWarpOptions& options) {
  options.Check();
  impl_ = std::make_unique<Impl>(scene, reference, options);
  const int W = reference.width(), H = reference.height();
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(static_cast<size_t>(W) * H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) pixels.emplace_back(x, y);
  const Hits hits = scene.IntersectPixels(reference, pixels);
  for (int i = 0; i < W * H; ++i) {
    if (!hits.hit(i)) continue;
    impl_->pixel.push_back(i);
    impl_->point.push_back(hits.point(i));
  }
  Require(!impl_->pixel.empty(), "the reference camera sees no model surface");
}

ViewWarp::~ViewWarp() = default;

const Camera& ViewWarp::reference() const { return impl_->reference; }

int ViewWarp::model_pixels() const {
  return static_cast<int>(impl_->pixel.size());
}

ViewWarpResult ViewWarp::Warp(const cv::Mat& frame, const Camera& camera,
                              cv::Mat* out) const {
  const Impl& m = *impl_;
  ViewWarpResult result;
  const int W = m.reference.width(), H = m.reference.height();
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  if (frame.empty()) {
    out->create(H, W, CV_32FC1);
    out->setTo(kNaN);
    result.message = "frame not decodable";
    return result;
  }
  Require(frame.type() == CV_32FC1 && frame.cols == camera.width() &&
              frame.rows == camera.height(),
          "frame: expected float32 gray of its camera's size (" +
              std::to_string(camera.width()) + "x" +
              std::to_string(camera.height()) + ")");
  const int n = static_cast<int>(m.pixel.size());
  // Where each surface point lands in the frame (-1: not in the image).
  std::vector<Eigen::Vector2f> at(n, Eigen::Vector2f(-1.f, -1.f));
  const Eigen::Vector3d center = camera.center_in_world();
  const Eigen::Vector3f c = center.cast<float>();
  std::vector<float> origins, directions;
  std::vector<int> cast;  // points in the image, whose view is checked
  {
    std::vector<uint8_t> in_image(n, 0);
    tbb::parallel_for(
        tbb::blocked_range<int>(0, n, 4096),
        [&](const tbb::blocked_range<int>& r) {
          for (int i = r.begin(); i < r.end(); ++i) {
            Eigen::Vector2d px;
            if (!camera.WorldToPixel(m.point[i].cast<double>(), &px)) continue;
            // Bilinear needs the four pixels around px.
            if (px.x() < 0 || px.y() < 0 || px.x() > camera.width() - 1 ||
                px.y() > camera.height() - 1)
              continue;
            at[i] = px.cast<float>();
            in_image[i] = 1;
          }
        });
    for (int i = 0; i < n; ++i)
      if (in_image[i]) cast.push_back(i);
  }
  const int64_t k = static_cast<int64_t>(cast.size());
  origins.resize(3 * k);
  directions.resize(3 * k);
  for (int64_t j = 0; j < k; ++j) {
    const Eigen::Vector3f d = m.point[cast[j]] - c;
    for (int a = 0; a < 3; ++a) {
      origins[3 * j + a] = c[a];
      directions[3 * j + a] = d[a];
    }
  }
  std::vector<float> distance(k);
  HitBuffers buffers;
  buffers.distance = distance.data();
  if (k > 0)
    m.scene.Intersect(k, origins.data(), directions.data(), 0.f,
                      std::numeric_limits<float>::infinity(), buffers);
  cv::Mat map_x(H, W, CV_32FC1, cv::Scalar(-10.f));
  cv::Mat map_y(H, W, CV_32FC1, cv::Scalar(-10.f));
  int seen = 0;
  const float keep = static_cast<float>(1.0 - m.options.hidden_share);
  for (int64_t j = 0; j < k; ++j) {
    const int i = cast[j];
    const float to_point = (m.point[i] - c).norm();
    // The camera's first hit is the point itself (within a share of its
    // distance), not something in front of it.
    if (!(distance[j] >= keep * to_point)) continue;
    const int p = m.pixel[i];
    map_x.at<float>(p / W, p % W) = at[i].x();
    map_y.at<float>(p / W, p % W) = at[i].y();
    ++seen;
  }
  cv::remap(frame, *out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar(kNaN));
  result.seen_share = static_cast<double>(seen) / n;
  if (result.seen_share < m.options.min_seen_share) {
    result.status = ViewWarpResult::Status::kOutOfView;
    result.message = "the camera sees " +
                     std::to_string(static_cast<int>(
                         std::lround(100.0 * result.seen_share))) +
                     "% of the model it sees on the reference frame";
    return result;
  }
  result.status = ViewWarpResult::Status::kOk;
  return result;
}

WarpedSource::WarpedSource(FrameSource* inner, const ViewWarp* warp,
                           std::vector<std::optional<Camera>> cameras_by_index,
                           std::vector<std::string> why_not)
    : inner_(inner),
      warp_(warp),
      cameras_(std::move(cameras_by_index)),
      why_not_(std::move(why_not)) {
  Require(inner_ != nullptr && warp_ != nullptr,
          "WarpedSource needs a source and a warp");
}

bool WarpedSource::Next(StreamedFrame* frame) {
  if (!inner_->Next(frame)) return false;
  if (frame->status != StreamedFrame::Status::kOk) return true;
  // The source's 8-bit luma is the unwarped frame: only gray is handed on.
  frame->luma.release();
  frame->table.release();
  const int i = frame->index;
  if (i < 0 || i >= static_cast<int>(cameras_.size()) || !cameras_[i]) {
    frame->status = StreamedFrame::Status::kUnusable;
    const bool said =
        i >= 0 && i < static_cast<int>(why_not_.size()) && !why_not_[i].empty();
    frame->message = said ? why_not_[i]
                          : "the camera has no pose on this frame (not solved)";
    frame->gray.release();
    return true;
  }
  cv::Mat warped;
  const ViewWarpResult r = warp_->Warp(frame->gray, *cameras_[i], &warped);
  if (r.status != ViewWarpResult::Status::kOk) {
    frame->status = StreamedFrame::Status::kUnusable;
    frame->message = r.message;
    frame->gray.release();
    return true;
  }
  frame->gray = warped;
  return true;
}

}  // namespace sunlapse
