#include "sunlapse/motion/view_warp.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "sunlapse/common/require.h"

namespace sunlapse {

void ViewWarpOptions::Check() const {
  Require(min_seen_share >= 0.0 && min_seen_share <= 1.0,
          "min_seen_share must be within [0, 1]");
  Require(hidden_share > 0.0 && hidden_share < 0.5,
          "hidden_share must be within (0, 0.5)");
  Require(depth_step >= 1 && depth_step <= 16,
          "depth_step must be within [1, 16]");
}

namespace {
// Coarse depth samples within this share of each other are one smooth
// surface (a ground seen at a grazing angle varies by 1-2% over a few
// pixels); further apart they straddle an outline.
constexpr float kSmooth = 0.05f;
}  // namespace

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
                              cv::Mat* out, Scratch* scratch) const {
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
  const int fw = camera.width(), fh = camera.height();
  // The frame camera's distance to the model on a coarse grid of its pixels
  // (every depth_step-th, the last row and column included): a point is
  // seen when it is no further than the model there. A ray per point would
  // cost ten times as much (a 960x540 frame: 90 ms of the 110 a frame).
  const int step = m.options.depth_step;
  const int gw = (fw - 1 + step - 1) / step + 1,
            gh = (fh - 1 + step - 1) / step + 1;
  auto grid_x = [&](int i) { return std::min(i * step, fw - 1); };
  auto grid_y = [&](int j) { return std::min(j * step, fh - 1); };
  // Buffers kept between frames: fresh ones cost their page faults again
  // (a 960x540 frame's are 10 MB).
  Scratch local_scratch;
  Scratch& sc = scratch != nullptr ? *scratch : local_scratch;
  std::vector<Eigen::Vector2d>& grid = sc.grid;
  if (sc.grid_size != Eigen::Vector2i(fw, fh)) {  // the same for every frame
    grid.clear();
    grid.reserve(static_cast<size_t>(gw) * gh);
    for (int j = 0; j < gh; ++j)
      for (int i = 0; i < gw; ++i) grid.emplace_back(grid_x(i), grid_y(j));
    sc.grid_size = Eigen::Vector2i(fw, fh);
  }
  std::vector<float>& depth = sc.depth;
  depth.resize(grid.size());
  {
    HitBuffers buffers;
    buffers.distance = depth.data();
    m.scene.IntersectPixels(camera, static_cast<int64_t>(grid.size()),
                            grid.front().data(), buffers);
  }
  const Eigen::Vector3f c = camera.center_in_world().cast<float>();
  const Eigen::Matrix3f KR =
      (camera.K() * camera.cam_from_world().linear()).cast<float>();
  const Eigen::Vector3f Kt =
      (camera.K() * camera.cam_from_world().translation()).cast<float>();
  const bool distorted = camera.distortion().has_value();
  const float tol = static_cast<float>(m.options.hidden_share);
  // Sampled in the same pass as the projection (no maps, no remap).
  out->create(H, W, CV_32FC1);
  out->setTo(kNaN);
  float* const dst = out->ptr<float>();
  auto sample = [&frame, fw, fh](float u, float v) {
    const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
    const int x1 = std::min(x0 + 1, fw - 1), y1 = std::min(y0 + 1, fh - 1);
    const float a = u - x0, b = v - y0;
    const float* r0 = frame.ptr<float>(y0);
    const float* r1 = frame.ptr<float>(y1);
    return (1 - b) * ((1 - a) * r0[x0] + a * r0[x1]) +
           b * ((1 - a) * r1[x0] + a * r1[x1]);
  };
  std::vector<Eigen::Vector2f>& at = sc.at;
  at.resize(n);
  std::vector<uint8_t>& outline = sc.outline;
  outline.assign(n, 0);
  std::atomic<int> seen{0};
  tbb::parallel_for(
      tbb::blocked_range<int>(0, n, 8192),
      [&](const tbb::blocked_range<int>& r) {
        int local = 0;
        for (int i = r.begin(); i < r.end(); ++i) {
          const Eigen::Vector3f& X = m.point[i];
          const Eigen::Vector3f h = KR * X + Kt;  // z: depth along the axis
          if (h.z() <= 1e-6f) continue;
          float u = h.x() / h.z(), v = h.y() / h.z();
          if (distorted) {
            Eigen::Vector2d px;
            if (!camera.WorldToPixel(X.cast<double>(), &px)) continue;
            u = static_cast<float>(px.x()), v = static_cast<float>(px.y());
          }
          // Bilinear sampling needs the four pixels around (u, v).
          if (!(u >= 0.f && v >= 0.f && u <= fw - 1 && v <= fh - 1)) continue;
          const int i0 = std::min(static_cast<int>(u) / step, gw - 2);
          const int j0 = std::min(static_cast<int>(v) / step, gh - 2);
          const float x0 = grid_x(i0), x1 = grid_x(i0 + 1);
          const float y0 = grid_y(j0), y1 = grid_y(j0 + 1);
          const float d00 = depth[j0 * gw + i0], d10 = depth[j0 * gw + i0 + 1];
          const float d01 = depth[(j0 + 1) * gw + i0];
          const float d11 = depth[(j0 + 1) * gw + i0 + 1];
          const float lo = std::min({d00, d10, d01, d11});
          const float hi = std::max({d00, d10, d01, d11});
          if (!(hi <= lo * (1.f + kSmooth))) {
            outline[i] = 1;  // the samples straddle an outline: a ray decides
            at[i] = Eigen::Vector2f(u, v);
            continue;
          }
          // One smooth surface around: its distance there, interpolated.
          const float a = (u - x0) / std::max(1.f, x1 - x0);
          const float b = (v - y0) / std::max(1.f, y1 - y0);
          const float model = (1 - b) * ((1 - a) * d00 + a * d10) +
                              b * ((1 - a) * d01 + a * d11);
          const float reach = model * (1.f + tol);
          if (!((X - c).squaredNorm() <= reach * reach)) continue;
          const int p = m.pixel[i];
          dst[p] = sample(u, v);
          ++local;
        }
        seen += local;
      });
  // Points near an outline of the model in the frame: a ray each.
  std::vector<int>& cast = sc.cast;
  cast.clear();
  for (int i = 0; i < n; ++i)
    if (outline[i]) cast.push_back(i);
  const int64_t k = static_cast<int64_t>(cast.size());
  std::vector<float>&origins = sc.origins, &directions = sc.directions,
  &distance = sc.distance;
  origins.resize(3 * k);
  directions.resize(3 * k);
  distance.resize(k);
  for (int64_t j = 0; j < k; ++j) {
    const Eigen::Vector3f d = m.point[cast[j]] - c;
    for (int a = 0; a < 3; ++a) {
      origins[3 * j + a] = c[a];
      directions[3 * j + a] = d[a];
    }
  }
  if (k > 0) {
    HitBuffers buffers;
    buffers.distance = distance.data();
    m.scene.Intersect(k, origins.data(), directions.data(), 0.f,
                      std::numeric_limits<float>::infinity(), buffers);
  }
  int seen_near_outlines = 0;
  for (int64_t j = 0; j < k; ++j) {
    const int i = cast[j];
    // The camera's first hit is the point itself, not something in front.
    if (!(distance[j] >= (1.f - tol) * (m.point[i] - c).norm())) continue;
    const int p = m.pixel[i];
    dst[p] = sample(at[i].x(), at[i].y());
    ++seen_near_outlines;
  }
  seen += seen_near_outlines;
  result.seen_share = static_cast<double>(seen.load()) / n;
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
                           std::vector<std::string> why_not, int queue_frames)
    : inner_(inner),
      warp_(warp),
      cameras_(std::move(cameras_by_index)),
      why_not_(std::move(why_not)),
      queue_frames_(queue_frames) {
  Require(inner_ != nullptr && warp_ != nullptr,
          "WarpedSource needs a source and a warp");
  Require(queue_frames_ >= 0, "queue_frames must be 0 or more");
  if (queue_frames_ > 0) worker_ = std::thread([this] { Work(); });
}

WarpedSource::~WarpedSource() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  if (worker_.joinable()) worker_.join();
}

bool WarpedSource::Produce(StreamedFrame* frame) {
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
  const auto t0 = std::chrono::steady_clock::now();
  const ViewWarpResult r =
      warp_->Warp(frame->gray, *cameras_[i], &warped, &scratch_);
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    seconds_ += took;
  }
  if (r.status != ViewWarpResult::Status::kOk) {
    frame->status = StreamedFrame::Status::kUnusable;
    frame->message = r.message;
    frame->gray.release();
    return true;
  }
  frame->gray = warped;
  return true;
}

void WarpedSource::Work() {
  for (;;) {
    StreamedFrame frame;
    bool more = false;
    std::exception_ptr error;
    try {
      more = Produce(&frame);
    } catch (...) {
      error = std::current_exception();
    }
    std::unique_lock<std::mutex> lock(mutex_);
    if (error || !more) {
      error_ = error;
      done_ = true;
      changed_.notify_all();
      return;
    }
    changed_.wait(lock, [this] {
      return stop_ || static_cast<int>(queue_.size()) < queue_frames_;
    });
    if (stop_) return;
    queue_.push_back(std::move(frame));
    changed_.notify_all();
  }
}

bool WarpedSource::Next(StreamedFrame* frame) {
  if (queue_frames_ == 0) return Produce(frame);
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return !queue_.empty() || done_; });
  if (!queue_.empty()) {
    *frame = std::move(queue_.front());
    queue_.pop_front();
    changed_.notify_all();
    return true;
  }
  if (error_) std::rethrow_exception(error_);
  return false;
}

double WarpedSource::seconds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return seconds_;
}

}  // namespace sunlapse
