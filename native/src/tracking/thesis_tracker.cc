#include "sunlapse/tracking/thesis_tracker.h"
#include "sunlapse/common/require.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "casters.h"
#include "sunlapse/common/angles.h"

namespace sunlapse {
namespace {

constexpr double kDeg = M_PI / 180.0;

double WrapDeg(double a) {
  a = std::fmod(a, 360.0);
  return a < 0 ? a + 360.0 : a;
}

// Eq. 4.4: counter-clockwise angle from +x of the vector s -> f, with the
// image's y axis (down) flipped so that counter-clockwise reads as usual.
double ImageAngleDeg(const Eigen::Vector2d& s, const Eigen::Vector2d& f) {
  return WrapDeg(std::atan2(-(f.y() - s.y()), f.x() - s.x()) / kDeg);
}

double MeanAlong(const cv::Mat& e, const Eigen::Vector2d& a,
                 const Eigen::Vector2d& b) {
  cv::LineIterator it(e.size(), cv::Point(cvRound(a.x()), cvRound(a.y())),
                      cv::Point(cvRound(b.x()), cvRound(b.y())), 8);
  double sum = 0;
  for (int i = 0; i < it.count; ++i, ++it) sum += e.at<float>(it.pos());
  return it.count > 0 ? sum / it.count : 0.0;
}

}  // namespace

void ThesisTrackerOptions::Check() const {
  Require(!ground_object_ids.empty(),
          "ground_object_ids: name at least one ground object");
  Require(max_direction_error_deg > 0, "max_direction_error_deg must be > 0");
  Require(slope_start >= 2 && slope_window >= 2,
          "slope_start and slope_window must be >= 2");
  Require(max_slope_change_deg > 0, "max_slope_change_deg must be > 0");
  Require(max_length_px > 0 && ignore_top_rows >= 0,
          "max_length_px > 0, ignore_top_rows >= 0");
}

cv::Mat EnergyImage(const cv::Mat& gray) {
  cv::Mat dx, dy;
  cv::Sobel(gray, dx, CV_32F, 1, 0, 1, 0.5);  // (I(x+1) - I(x-1)) / 2
  cv::Sobel(gray, dy, CV_32F, 0, 1, 1, 0.5);
  return cv::abs(dx) + cv::abs(dy);
}

int SelectShadow(const std::vector<ShadowCandidate>& c,
                 double max_direction_error_deg, std::vector<int>* dropped_by) {
  const int n = static_cast<int>(c.size());
  dropped_by->assign(n, 0);
  auto alive = [&](int i) { return (*dropped_by)[i] == 0; };
  auto drop_if = [&](int criterion, auto&& pred) {
    for (int i = 0; i < n; ++i) {
      if (alive(i) && pred(c[i])) (*dropped_by)[i] = criterion;
    }
  };
  auto mean_of = [&](auto&& field) {
    double sum = 0;
    int k = 0;
    for (int i = 0; i < n; ++i) {
      if (alive(i)) {
        sum += field(c[i]);
        ++k;
      }
    }
    return k ? sum / k : 0.0;
  };
  // 1. within 10 deg of the Sun's direction; 2. no end on the border.
  drop_if(1, [&](const ShadowCandidate& s) {
    return s.direction_error_deg > max_direction_error_deg;
  });
  drop_if(2, [](const ShadowCandidate& s) { return s.on_border; });
  // 3. energy at least the average; 4. length at least the average.
  const double energy =
      mean_of([](const ShadowCandidate& s) { return s.energy; });
  drop_if(3, [&](const ShadowCandidate& s) { return s.energy < energy; });
  const double length =
      mean_of([](const ShadowCandidate& s) { return s.length_px; });
  drop_if(4, [&](const ShadowCandidate& s) { return s.length_px < length; });
  // 5. exactly one end on a modelled object, else none, else any: strongest.
  int best = -1;
  for (int want : {1, 0, -1}) {
    for (int i = 0; i < n; ++i) {
      if (!alive(i) || (want >= 0 && c[i].ends_on_model != want)) continue;
      if (best < 0 || c[i].energy > c[best].energy) best = i;
    }
    if (best >= 0) break;
  }
  for (int i = 0; i < n; ++i) {
    if (alive(i) && i != best) (*dropped_by)[i] = 5;
  }
  return best;
}

struct ThesisTracker::Impl {
  const Scene& scene;
  const Camera& camera;
  ThesisTrackerOptions o;
  std::vector<ShadowCandidate> candidates;
  bool ready = false;
  cv::Mat prev_energy;
  Eigen::Vector2d s{0, 0};  // start pixel
  double theta_prev = 0;    // image angle of the shadow (deg)
  double zenith = 0, azimuth = 0;
  double object_length = 0;  // l_v, in pixels
  double energy_threshold = 0;

  Impl(const Scene& sc, const Camera& c, const ThesisTrackerOptions& opt)
      : scene(sc), camera(c), o(opt) {}

  bool OnBorder(const Eigen::Vector2d& p) const {
    return p.x() < 2 || p.y() < 2 + o.ignore_top_rows ||
           p.x() > camera.width() - 3 || p.y() > camera.height() - 3;
  }

  // Whether a modelled (non-ground) object is seen within 3 px of p.
  bool TouchesModel(const Eigen::Vector2d& p) const {
    std::vector<Eigen::Vector2d> around;
    for (int dy = -3; dy <= 3; dy += 3) {
      for (int dx = -3; dx <= 3; dx += 3)
        around.emplace_back(p.x() + dx, p.y() + dy);
    }
    const Hits h = scene.IntersectPixels(camera, around);
    for (size_t i = 0; i < around.size(); ++i) {
      if (h.hit(i) && !internal::IsGround(o.ground_object_ids, h.object_id[i]))
        return true;
    }
    return false;
  }

  Eigen::Vector2d FirstGroundPixel(const Eigen::Vector2d& a,
                                   const Eigen::Vector2d& b) const {
    cv::LineIterator it(cv::Size(camera.width(), camera.height()),
                        cv::Point(cvRound(a.x()), cvRound(a.y())),
                        cv::Point(cvRound(b.x()), cvRound(b.y())), 8);
    std::vector<Eigen::Vector2d> line;
    for (int i = 0; i < it.count; ++i, ++it)
      line.emplace_back(it.pos().x, it.pos().y);
    if (line.empty()) return a;
    const Hits h = scene.IntersectPixels(camera, line);
    for (size_t i = 0; i < line.size(); ++i) {
      if (h.hit(i) && internal::IsGround(o.ground_object_ids, h.object_id[i]))
        return line[i];
    }
    return a;
  }

  // Algorithm 1, lines 7-13: walks from s in direction theta (deg).
  Eigen::Vector2d Walk(const cv::Mat& e, double theta) const {
    const int W = e.cols, H = e.rows;
    const cv::Point nb[8] = {{1, 0},  {1, -1}, {0, -1}, {-1, -1},
                             {-1, 0}, {-1, 1}, {0, 1},  {1, 1}};
    cv::Point p(cvRound(s.x()), cvRound(s.y()));
    std::vector<cv::Point> path{p};
    std::set<std::pair<int, int>> visited{{p.x, p.y}};
    auto direction = [](const cv::Point& a, const cv::Point& b) {
      return std::atan2(-(b.y - a.y), b.x - a.x) / kDeg;
    };
    while (static_cast<int>(path.size()) < o.max_length_px) {
      // The four neighbours closest to the search direction.
      std::vector<std::pair<double, int>> order;
      for (int k = 0; k < 8; ++k) {
        const double ang = std::atan2(-nb[k].y, nb[k].x) / kDeg;
        order.emplace_back(std::abs(std::remainder(ang - theta, 360.0)), k);
      }
      std::sort(order.begin(), order.end());
      cv::Point next(-1, -1);
      float best = -1;
      for (int c = 0; c < 4; ++c) {
        const cv::Point q = p + nb[order[c].second];
        if (q.x < 0 || q.y < o.ignore_top_rows || q.x >= W || q.y >= H)
          continue;
        if (visited.count({q.x, q.y})) continue;
        const float v = e.at<float>(q);
        if (v > best) {
          best = v;
          next = q;
        }
      }
      if (next.x < 0) break;  // the frame's border
      path.push_back(next);
      visited.insert({next.x, next.y});
      p = next;
      if (best < energy_threshold) break;  // termination 1
      const int n = static_cast<int>(path.size());
      if (n >= o.slope_start + o.slope_window &&
          (n - o.slope_start) % o.slope_window == 0) {
        const double first = direction(path[0], path[o.slope_start - 1]);
        const double last = direction(path[n - o.slope_window], path[n - 1]);
        if (std::abs(std::remainder(last - first, 360.0)) >
            o.max_slope_change_deg)
          break;  // 2
      }
    }
    return {static_cast<double>(p.x), static_cast<double>(p.y)};
  }
};

ThesisTracker::ThesisTracker(const Scene& scene, const Camera& camera,
                             const ThesisTrackerOptions& options)
    : impl_(std::make_unique<Impl>(scene, camera, options)) {
  options.Check();
}

ThesisTracker::~ThesisTracker() = default;

const std::vector<ShadowCandidate>& ThesisTracker::candidates() const {
  return impl_->candidates;
}

TrackedFrame ThesisTracker::Initialize(const cv::Mat& frame,
                                       const Eigen::Vector3d& sun) {
  Impl& t = *impl_;
  Require(frame.type() == CV_32FC1 && frame.cols == t.camera.width() &&
              frame.rows == t.camera.height(),
          "frame: expected float32 gray of the camera's size");
  Require(sun.allFinite() && sun.z() > 0,
          "sun_in_world must point above the horizon");
  const auto t0 = std::chrono::steady_clock::now();
  TrackedFrame out;
  const Eigen::Vector3d d = sun.normalized();
  AnglesFromSunInWorld(d, &t.zenith, &t.azimuth);
  out.sun_in_world = d;
  out.zenith_deg = t.zenith;
  out.azimuth_deg = t.azimuth;
  const cv::Mat e = EnergyImage(frame);
  // Candidates: the model's shadows under the initial Sun (our stand-in for
  // Lalonde et al.'s detector).
  const Eigen::Vector3f away(-d.x(), -d.y(), 0.f);
  for (const internal::Caster& c :
       internal::FindCasters(t.scene, t.o.ground_object_ids)) {
    Eigen::Vector3f top, tip;
    if (!internal::ShadowTip(t.scene, c, d, t.o.ground_object_ids, &top, &tip))
      continue;
    const Eigen::Vector3f foot = c.FootBelow(top);
    Eigen::Vector2d a, b, dir_px;
    if (!t.camera.WorldToPixel(foot.cast<double>(), &a) ||
        !t.camera.WorldToPixel(tip.cast<double>(), &b) ||
        !t.camera.WorldToPixel((foot + away.normalized()).cast<double>(),
                               &dir_px)) {
      continue;
    }
    // The shadow starts where it becomes visible: the first pixel from the
    // foot toward the tip that sees the ground (the foot itself from the side,
    // the caster's silhouette from above).
    a = t.FirstGroundPixel(a, b);
    ShadowCandidate sc;
    sc.start_px = a;
    sc.end_px = b;
    sc.length_px = (b - a).norm();
    if (sc.length_px < 1) continue;
    sc.direction_error_deg = std::abs(
        std::remainder(ImageAngleDeg(a, b) - ImageAngleDeg(a, dir_px), 360.0));
    sc.on_border = t.OnBorder(a) || t.OnBorder(b);
    sc.energy = sc.on_border ? 0.0 : MeanAlong(e, a, b);
    sc.ends_on_model =
        1 + (t.TouchesModel(b) ? 1 : 0);  // the start is at its caster
    t.candidates.push_back(sc);
  }
  std::vector<int> dropped;
  const int pick =
      SelectShadow(t.candidates, t.o.max_direction_error_deg, &dropped);
  if (pick < 0) {
    out.status = TrackedFrame::Status::kNoShadowInView;
    out.reason = "no ground shadow passes the five criteria";
    return out;
  }
  const ShadowCandidate& sc = t.candidates[pick];
  t.s = sc.start_px;
  t.theta_prev = ImageAngleDeg(sc.start_px, sc.end_px);
  t.object_length = sc.length_px / std::tan(std::max(t.zenith, 0.5) * kDeg);
  t.energy_threshold = 0.5 * sc.energy;
  t.prev_energy = e;
  t.ready = true;
  out.ok = true;
  out.status = TrackedFrame::Status::kTracked;
  out.confidence = 1.0;
  out.shadow_start_px = sc.start_px;
  out.shadow_end_px = sc.end_px;
  out.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  return out;
}

TrackedFrame ThesisTracker::Track(const cv::Mat& frame) {
  Impl& t = *impl_;
  const auto t0 = std::chrono::steady_clock::now();
  TrackedFrame out;
  out.zenith_deg = t.zenith;
  out.azimuth_deg = t.azimuth;
  auto finish = [&]() {
    out.sun_in_world = SunInWorldFromAngles(out.zenith_deg, out.azimuth_deg);
    out.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
            .count();
    return out;
  };
  if (!t.ready) {
    out.status = TrackedFrame::Status::kNoShadowInView;
    out.reason = "no shadow was selected on the first frame";
    return finish();
  }
  if (frame.empty()) {
    out.status = TrackedFrame::Status::kUnusableFrame;
    out.reason = "frame cannot be decoded";
    return finish();
  }
  Require(frame.type() == CV_32FC1 && frame.size() == t.prev_energy.size(),
          "frame: expected float32 gray of the camera's size");
  const cv::Mat e = EnergyImage(frame);
  // Line 5: keep s while its energy holds, else the 5x5 energy centre of mass.
  const cv::Point sp(cvRound(t.s.x()), cvRound(t.s.y()));
  if (std::abs(e.at<float>(sp) - t.prev_energy.at<float>(sp)) > 1e-6f) {
    const cv::Rect win =
        cv::Rect(sp.x - 2, sp.y - 2, 5, 5) & cv::Rect(0, 0, e.cols, e.rows);
    double m = 0, mx = 0, my = 0;
    for (int y = win.y; y < win.y + win.height; ++y) {
      for (int x = win.x; x < win.x + win.width; ++x) {
        const double v = e.at<float>(y, x);
        m += v;
        mx += v * x;
        my += v * y;
      }
    }
    if (m > 0) t.s = {std::round(mx / m), std::round(my / m)};
  }
  t.prev_energy = e;
  const Eigen::Vector2d f = t.Walk(e, t.theta_prev);
  const double length = (f - t.s).norm();
  out.shadow_start_px = t.s;
  out.shadow_end_px = f;
  if (length < 2) {
    out.status = TrackedFrame::Status::kNoMatch;
    out.reason = "shadow lost: the walk found no shadow pixels";
    return finish();
  }
  const double theta = ImageAngleDeg(t.s, f);
  t.zenith = std::atan(length / t.object_length) / kDeg;
  t.azimuth = WrapDeg(t.azimuth - std::remainder(theta - t.theta_prev, 360.0));
  t.theta_prev = theta;
  out.ok = true;
  out.status = TrackedFrame::Status::kTracked;
  out.confidence = 1.0;  // the thesis gives none
  out.zenith_deg = t.zenith;
  out.azimuth_deg = t.azimuth;
  return finish();
}

}  // namespace sunlapse
