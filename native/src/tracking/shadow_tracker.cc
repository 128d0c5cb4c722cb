#include "sunlapse/tracking/shadow_tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "casters.h"
#include "sunlapse/common/robust_fit.h"

namespace sunlapse {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr float kInf = std::numeric_limits<float>::infinity();

void Require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

void AnglesOf(const Eigen::Vector3d& d, double* zenith, double* azimuth) {
  *zenith = std::acos(std::clamp(d.z(), -1.0, 1.0)) / kDeg;
  const double a = std::atan2(d.x(), d.y()) / kDeg;
  *azimuth = a < 0 ? a + 360.0 : a;
}

}  // namespace

void ShadowTrackerOptions::Check() const {
  Require(!ground_object_ids.empty(), "ground_object_ids: name at least one ground object");
  Require(band_radius_px >= 1 && band_radius_px <= 50, "band_radius_px must be in [1, 50]");
  Require(max_band_pixels >= 100, "max_band_pixels must be >= 100");
  Require(search_step_deg > 0 && tolerance_deg > 0 && tolerance_deg <= search_step_deg,
          "need 0 < tolerance_deg <= search_step_deg");
  Require(loss_scale > 0, "loss_scale must be > 0");
  Require(min_contrast >= 0, "min_contrast must be >= 0");
  Require(subsamples >= 1 && subsamples <= 4, "subsamples must be in [1, 4]");
  Require(ignore_top_rows >= 0 && ignore_bottom_rows >= 0,
          "ignore_top_rows/ignore_bottom_rows must be >= 0");
}

struct ShadowTracker::Impl {
  const Scene& scene;
  const Camera& camera;
  ShadowTrackerOptions o;
  int W = 0, H = 0;

  // The ground as the camera sees it, one entry per ground pixel.
  cv::Mat1i ground_index;              // H x W, -1 elsewhere
  std::vector<cv::Point> pixel;
  std::vector<float> origin;           // x3: point lifted along the normal
  std::vector<Eigen::Vector3f> normal;
  std::vector<Eigen::Vector3f> dpdx, dpdy;  // ground point per pixel step
  std::vector<float> albedo;           // relative, median 1
  std::vector<internal::Caster> casters;

  // Tracking state.
  bool initialized = false;
  Eigen::Vector3d sun, sun_before;     // last two accepted Suns
  bool have_velocity = false;
  int lost = 0;
  std::vector<int> band;               // ground indices near shadow boundaries

  // Work buffers: band_origin/ray_x/band_normal per sub-pixel ray,
  // band_x/band_y per band pixel.
  std::vector<float> band_origin, ray_x, band_x, band_y;
  std::vector<Eigen::Vector3f> band_normal;
  std::vector<uint8_t> occluded;
  AffineFit fit;

  Impl(const Scene& s, const Camera& c, const ShadowTrackerOptions& opt)
      : scene(s), camera(c), o(opt), W(c.width()), H(c.height()) {}

  bool IsGround(int32_t id) const { return internal::IsGround(o.ground_object_ids, id); }

  void MapGround() {
    ground_index = cv::Mat1i(H, W, -1);
    std::vector<double> px;
    const int y0 = o.ignore_top_rows, y1 = H - o.ignore_bottom_rows;
    for (int y = y0; y < y1; ++y) {
      for (int x = 0; x < W; ++x) px.insert(px.end(), {double(x), double(y)});
    }
    const int64_t n = static_cast<int64_t>(px.size() / 2);
    Hits hits(n);
    scene.IntersectPixels(camera, n, px.data(), hits.buffers());
    const float lift = 2e-4f * scene.bounds().diagonal().norm() + 1e-4f;
    for (int64_t i = 0; i < n; ++i) {
      if (!hits.hit(i) || !IsGround(hits.object_id[i])) continue;
      const int x = static_cast<int>(px[2 * i]), y = static_cast<int>(px[2 * i + 1]);
      ground_index(y, x) = static_cast<int>(pixel.size());
      pixel.emplace_back(x, y);
      const Eigen::Vector3f p = hits.point(i) + lift * hits.normal(i);
      origin.insert(origin.end(), {p.x(), p.y(), p.z()});
      normal.push_back(hits.normal(i));
    }
    // How the ground point moves per pixel, from neighbouring ground pixels.
    dpdx.assign(pixel.size(), Eigen::Vector3f::Zero());
    dpdy.assign(pixel.size(), Eigen::Vector3f::Zero());
    auto point = [&](int g) { return Eigen::Vector3f(&origin[3 * g]); };
    auto derivative = [&](int g, int dx, int dy) -> Eigen::Vector3f {
      const cv::Point p = pixel[g];
      const cv::Point a(p.x - dx, p.y - dy), b(p.x + dx, p.y + dy);
      const cv::Rect frame(0, 0, W, H);
      const int ga = frame.contains(a) ? ground_index(a) : -1;
      const int gb = frame.contains(b) ? ground_index(b) : -1;
      if (ga >= 0 && gb >= 0) return 0.5f * (point(gb) - point(ga));
      if (gb >= 0) return point(gb) - point(g);
      if (ga >= 0) return point(g) - point(ga);
      return Eigen::Vector3f::Zero();
    };
    for (int g = 0; g < static_cast<int>(pixel.size()); ++g) {
      dpdx[g] = derivative(g, 1, 0);
      dpdy[g] = derivative(g, 0, 1);
    }
  }

  // Shading of ground pixel g toward `toward_sun` given its occlusion flag.
  float Shading(int g, const Eigen::Vector3f& d, bool occ) const {
    return occ ? 0.f : std::max(0.f, normal[g].dot(d));
  }

  // Lit flags of ground indices `ids` toward d (1 lit, 0 shadow).
  std::vector<uint8_t> LitOf(const std::vector<int>& ids, const Eigen::Vector3f& d) {
    std::vector<float> org(3 * ids.size());
    for (size_t i = 0; i < ids.size(); ++i) {
      for (int k = 0; k < 3; ++k) org[3 * i + k] = origin[3 * ids[i] + k];
    }
    std::vector<uint8_t> occ(ids.size());
    scene.OccludedToward(static_cast<int64_t>(ids.size()), org.data(), d, 0.f, kInf, occ.data());
    for (auto& v : occ) v = !v;
    return occ;
  }

  // Band: ground pixels within band_radius of a lit/shadow boundary toward
  // d, searched among `candidates` (ground indices).
  std::vector<int> BandAround(const std::vector<int>& candidates, const Eigen::Vector3f& d) {
    if (candidates.empty()) return {};
    const std::vector<uint8_t> lit = LitOf(candidates, d);
    cv::Rect roi;
    for (size_t i = 0; i < candidates.size(); ++i) {
      roi |= cv::Rect(pixel[candidates[i]], cv::Size(1, 1));
    }
    cv::Mat1b state(roi.size(), 255);  // 255 unknown, 0 shadow, 1 lit
    for (size_t i = 0; i < candidates.size(); ++i) {
      state(pixel[candidates[i]] - roi.tl()) = lit[i];
    }
    cv::Mat1b boundary(roi.size(), 0);
    for (int y = 0; y < state.rows; ++y) {
      for (int x = 0; x < state.cols; ++x) {
        const uint8_t s = state(y, x);
        if (s == 255) continue;
        const bool edge = (x + 1 < state.cols && state(y, x + 1) != 255 && state(y, x + 1) != s) ||
                          (y + 1 < state.rows && state(y + 1, x) != 255 && state(y + 1, x) != s);
        if (edge) {
          boundary(y, x) = 255;
          if (x + 1 < state.cols && state(y, x + 1) != s) boundary(y, x + 1) = 255;
          if (y + 1 < state.rows && state(y + 1, x) != s) boundary(y + 1, x) = 255;
        }
      }
    }
    return PixelsNear(boundary, roi, o.band_radius_px);
  }

  // Ground indices within `radius` of the set pixels of `mask` (placed at roi).
  std::vector<int> PixelsNear(const cv::Mat1b& mask, const cv::Rect& roi, int radius) {
    const cv::Rect grown = (roi + cv::Size(2 * radius, 2 * radius) - cv::Point(radius, radius)) &
                           cv::Rect(0, 0, W, H);
    cv::Mat1b big(grown.size(), 0);
    mask.copyTo(big(cv::Rect(roi.tl() - grown.tl(), roi.size())));
    cv::dilate(big, big, cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                                   cv::Size(2 * radius + 1, 2 * radius + 1)));
    std::vector<int> out;
    for (int y = 0; y < big.rows; ++y) {
      for (int x = 0; x < big.cols; ++x) {
        if (!big(y, x)) continue;
        const int g = ground_index(y + grown.y, x + grown.x);
        if (g >= 0) out.push_back(g);
      }
    }
    return out;
  }

  std::vector<int> AllGround(int stride) const {
    std::vector<int> out;
    for (int g = 0; g < static_cast<int>(pixel.size()); ++g) {
      if (pixel[g].x % stride == 0 && pixel[g].y % stride == 0) out.push_back(g);
    }
    return out;
  }

  // Loads the band's pixels (subsampled) and the frame's values into buffers,
  // with subsamples^2 rays per pixel spread over the pixel's footprint.
  void LoadBand(const cv::Mat& frame) {
    const int stride = std::max<int>(1, static_cast<int>(band.size() / o.max_band_pixels) + 1);
    const int k = o.subsamples;
    band_origin.clear();
    band_normal.clear();
    band_y.clear();
    for (size_t i = 0; i < band.size(); i += stride) {
      const int g = band[i];
      const Eigen::Vector3f p(&origin[3 * g]);
      for (int sy = 0; sy < k; ++sy) {
        for (int sx = 0; sx < k; ++sx) {
          const float ox = (sx + 0.5f) / k - 0.5f, oy = (sy + 0.5f) / k - 0.5f;
          const Eigen::Vector3f q = p + ox * dpdx[g] + oy * dpdy[g];
          band_origin.insert(band_origin.end(), {q.x(), q.y(), q.z()});
          band_normal.push_back(normal[g]);
        }
      }
      const float v = frame.at<float>(pixel[g]);
      band_y.push_back(o.normalize_albedo ? v / albedo[g] : v);
    }
    band_x.resize(band_y.size());
    ray_x.resize(band_normal.size());
    occluded.resize(band_normal.size());
  }

  double Cost(const Eigen::Vector3d& toward_sun, double scale) {
    const Eigen::Vector3f d = toward_sun.cast<float>();
    const int rays = static_cast<int>(band_normal.size());
    scene.OccludedToward(rays, band_origin.data(), d, 0.f, kInf, occluded.data());
    const int per_pixel = o.subsamples * o.subsamples;
    for (size_t i = 0; i < band_x.size(); ++i) {
      float sum = 0;
      for (int r = 0; r < per_pixel; ++r) {
        const size_t j = i * per_pixel + r;
        sum += occluded[j] ? 0.f : std::max(0.f, band_normal[j].dot(d));
      }
      band_x[i] = sum / per_pixel;
    }
    const int n = static_cast<int>(band_y.size());
    RobustAffineFit(n, band_x.data(), band_y.data(), nullptr, 1, scale, 3, &fit);
    return fit.cost;
  }

  // Compass search on the sphere in the tangent plane of `start`.
  Eigen::Vector3d Search(const Eigen::Vector3d& start, double step_deg, double scale) {
    Eigen::Vector3d e1 = start.cross(Eigen::Vector3d::UnitZ());
    if (e1.norm() < 1e-6) e1 = Eigen::Vector3d::UnitX();
    e1.normalize();
    const Eigen::Vector3d e2 = start.cross(e1).normalized();
    Eigen::Vector2d uv(0, 0);
    double best = Cost(start, scale);
    double h = step_deg * kDeg;
    const Eigen::Vector2d moves[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    int guard = 0;
    while (h > o.tolerance_deg * kDeg && guard++ < 300) {
      int pick = -1;
      double pick_cost = best;
      for (int m = 0; m < 4; ++m) {
        const Eigen::Vector2d c = uv + h * moves[m];
        const Eigen::Vector3d d = (start + c.x() * e1 + c.y() * e2).normalized();
        if (d.z() <= 0.01) continue;
        const double cost = Cost(d, scale);
        if (cost < pick_cost) {
          pick_cost = cost;
          pick = m;
        }
      }
      if (pick >= 0) {
        uv += h * moves[pick];
        best = pick_cost;
      } else {
        h *= 0.5;
      }
    }
    return (start + uv.x() * e1 + uv.y() * e2).normalized();
  }

  void Describe(const Eigen::Vector3d& d, TrackedFrame* out) {
    AnglesOf(d, &out->zenith_deg, &out->azimuth_deg);
    out->sun_in_world = d;
    // The longest modelled shadow whose tip lands on the ground in view.
    double longest = 0;
    for (const internal::Caster& c : casters) {
      Eigen::Vector3f top, tip;
      if (!internal::ShadowTip(scene, c, d, o.ground_object_ids, &top, &tip)) continue;
      const Eigen::Vector3f foot = c.FootBelow(top);
      Eigen::Vector2d foot_px, tip_px;
      if (!camera.WorldToPixel(foot.cast<double>(), &foot_px) ||
          !camera.WorldToPixel(tip.cast<double>(), &tip_px)) {
        continue;
      }
      if (tip_px.x() < 0 || tip_px.y() < 0 || tip_px.x() > W - 1 || tip_px.y() > H - 1) continue;
      const double length = (tip - foot).norm();
      if (length > longest) {
        longest = length;
        out->shadow_start_px = foot_px;
        out->shadow_end_px = tip_px;
      }
    }
  }

  // The frame cannot show shadows: why, or empty if it can.
  std::string Unusable(const cv::Mat& frame) const {
    if (frame.empty()) return "frame cannot be decoded";
    if (frame.cols != W || frame.rows != H) return "frame has another size than the clip";
    const cv::Mat content = frame.rowRange(o.ignore_top_rows, H - o.ignore_bottom_rows);
    double lo, hi;
    cv::minMaxLoc(content, &lo, &hi);
    if (hi < 0.01) return "frame is black";
    const double clipped = cv::countNonZero(content >= 0.98f) / static_cast<double>(content.total());
    if (clipped > 0.5) return "frame is overexposed";
    return {};
  }
};

ShadowTracker::ShadowTracker(const Scene& scene, const Camera& camera,
                             const ShadowTrackerOptions& options)
    : impl_(std::make_unique<Impl>(scene, camera, options)) {
  options.Check();
  Require(options.ignore_top_rows + options.ignore_bottom_rows < camera.height(),
          "ignore_top_rows + ignore_bottom_rows leave no rows");
}

ShadowTracker::~ShadowTracker() = default;

TrackedFrame ShadowTracker::Initialize(const cv::Mat& frame, const Eigen::Vector3d& sun_in_world) {
  Impl& s = *impl_;
  Require(frame.type() == CV_32FC1 && frame.cols == s.W && frame.rows == s.H,
          "frame: expected float32 gray of the camera's size");
  Require(sun_in_world.allFinite() && sun_in_world.z() > 0, "sun_in_world must point above the horizon");
  const auto t0 = std::chrono::steady_clock::now();
  TrackedFrame out;
  const Eigen::Vector3d d = sun_in_world.normalized();
  s.MapGround();
  s.casters = internal::FindCasters(s.scene, s.o.ground_object_ids);
  s.sun = s.sun_before = d;
  s.have_velocity = false;
  s.lost = 0;
  s.initialized = true;
  s.Describe(d, &out);
  if (s.pixel.empty()) {
    out.reason = "no ground in view: check the ground objects and the camera";
    return out;
  }
  // Shadows of the first frame, and the ground's albedo relative to its
  // median: I = rho (A + S shading) with A, S fitted robustly on the ground.
  const Eigen::Vector3f df = d.cast<float>();
  const std::vector<int> all = s.AllGround(1);
  const std::vector<uint8_t> lit = s.LitOf(all, df);
  std::vector<float> x(all.size()), y(all.size());
  for (size_t i = 0; i < all.size(); ++i) {
    x[i] = s.Shading(all[i], df, !lit[i]);
    y[i] = frame.at<float>(s.pixel[all[i]]);
  }
  std::vector<float> sorted = y;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double scale = std::max(1e-4, s.o.loss_scale * sorted[sorted.size() / 2]);
  AffineFit fit;
  RobustAffineFit(static_cast<int>(all.size()), x.data(), y.data(), nullptr, 1, scale, 4, &fit);
  s.band = s.BandAround(all, df);
  s.albedo.assign(s.pixel.size(), 1.f);
  cv::Mat1b near_edge(s.H, s.W, uint8_t(0));
  for (int g : s.band) near_edge(s.pixel[g]) = 1;  // unreliable: lit state uncertain
  for (size_t i = 0; i < all.size(); ++i) {
    const double model = fit.a[0] + fit.b[0] * x[i];
    if (model > 1e-4 && !near_edge(s.pixel[all[i]])) {
      s.albedo[all[i]] = std::clamp(static_cast<float>(y[i] / model), 0.05f, 20.f);
    }
  }
  out.contrast = fit.a[0] > 0 ? fit.b[0] / fit.a[0] : (fit.b[0] > 0 ? 100.0 : 0.0);
  out.band_pixels = static_cast<int>(s.band.size());
  out.ok = !s.band.empty();
  out.confidence = out.ok ? 1.0 : 0.0;
  if (!out.ok) out.reason = "no cast shadow of the model falls on the ground in view";
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

TrackedFrame ShadowTracker::Track(const cv::Mat& frame) {
  Impl& s = *impl_;
  Require(s.initialized, "Track() before Initialize()");
  Require(frame.empty() || frame.type() == CV_32FC1, "frame: expected float32 gray");
  const auto t0 = std::chrono::steady_clock::now();
  TrackedFrame out;
  // Prediction: the Sun keeps its last angular velocity.
  Eigen::Vector3d pred = s.sun;
  if (s.have_velocity) {
    const Eigen::Vector3d axis = s.sun_before.cross(s.sun);
    const double angle = std::atan2(axis.norm(), s.sun_before.dot(s.sun));
    if (axis.norm() > 1e-12) {
      pred = Eigen::AngleAxisd(angle * (1 + s.lost), axis.normalized()) * s.sun;
    }
  }
  auto finish = [&](const Eigen::Vector3d& d) {
    s.Describe(d, &out);
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
  };
  out.reason = s.Unusable(frame);
  if (!out.reason.empty()) {
    ++s.lost;
    return finish(pred);
  }
  const Eigen::Vector3f pf = pred.cast<float>();
  // Band near the predicted boundaries: found among the last band's
  // neighbourhood, or on the whole ground after a loss.
  std::vector<int> candidates;
  if (!s.band.empty() && s.lost == 0) {
    cv::Rect roi;
    for (int g : s.band) roi |= cv::Rect(s.pixel[g], cv::Size(1, 1));
    cv::Mat1b mask(roi.size(), uint8_t(0));
    for (int g : s.band) mask(s.pixel[g] - roi.tl()) = 255;
    candidates = s.PixelsNear(mask, roi, 2 * s.o.band_radius_px);
  } else {
    candidates = s.AllGround(1);
  }
  std::vector<int> band = s.BandAround(candidates, pf);
  if (band.empty() && s.lost == 0) band = s.BandAround(s.AllGround(1), pf);
  if (band.empty()) {
    ++s.lost;
    out.reason = "no cast shadow of the model falls on the ground in view";
    return finish(pred);
  }
  s.band = band;
  s.LoadBand(frame);
  std::vector<float> sorted = s.band_y;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double scale = std::max(1e-4, s.o.loss_scale * sorted[sorted.size() / 2]);
  const double step = s.o.search_step_deg * (s.lost > 0 ? 4.0 : 1.0);
  const Eigen::Vector3d found = s.Search(pred, step, scale);
  s.Cost(found, scale);  // leaves the fit of the found Sun in s.fit
  const double a = s.fit.a[0], b = s.fit.b[0];
  out.contrast = a > 0 ? b / a : (b > 0 ? 100.0 : 0.0);
  out.band_pixels = static_cast<int>(s.band_y.size());
  int inliers = 0;
  for (double r : s.fit.residual) inliers += std::abs(r) < 3 * scale;
  const double inlier_fraction = s.band_y.empty() ? 0.0 : double(inliers) / s.band_y.size();
  if (out.contrast < s.o.min_contrast) {
    ++s.lost;
    out.reason = "shadow lost: no sun/shade contrast on the ground (cloud, haze or glare?)";
    return finish(pred);
  }
  out.ok = true;
  out.confidence = inlier_fraction * std::min(1.0, out.contrast / (3 * s.o.min_contrast));
  // After a loss the velocity is unknown again: it restarts from this frame.
  s.have_velocity = s.lost == 0;
  s.sun_before = s.sun;
  s.sun = found;
  s.lost = 0;
  return finish(found);
}

}  // namespace sunlapse
