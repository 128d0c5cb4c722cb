#include "sunlapse/initial/initial_sun.h"
#include "sunlapse/common/require.h"

#include "sunlapse/common/angles.h"
#include "sunlapse/common/order_statistics.h"
#include "sunlapse/common/robust_fit.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace sunlapse {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Cancelled {};

// The pixels the fit uses: where each sees the model, and what it shows.
struct Samples {
  std::vector<Eigen::Vector2d> pixel;
  std::vector<float> origin;  // N x 3: point + offset along the normal
  std::vector<Eigen::Vector3f> normal;
  std::vector<float> intensity;
  std::vector<int> group;             // compact object index
  std::vector<int32_t> group_object;  // group -> object id
  int num_groups = 0;
  int size() const { return static_cast<int>(intensity.size()); }
};

Samples GatherSamples(const Scene& scene, const Camera& camera,
                      const cv::Mat& frame, const InitialSunOptions& o) {
  const int top = o.ignore_top_rows;
  const int bottom = frame.rows - o.ignore_bottom_rows;
  const double area = static_cast<double>(frame.cols) * (bottom - top);
  const int step =
      std::max(1, static_cast<int>(std::floor(std::sqrt(area / o.max_pixels))));
  std::vector<double> px;
  for (int y = top + step / 2; y < bottom; y += step) {
    for (int x = step / 2; x < frame.cols; x += step) {
      px.push_back(x);
      px.push_back(y);
    }
  }
  const int64_t n = static_cast<int64_t>(px.size() / 2);
  Hits hits(n);
  scene.IntersectPixels(camera, n, px.data(), hits.buffers());

  const float offset = scene.surface_offset();
  const Eigen::Vector3f eye = camera.center_in_world().cast<float>();
  Samples s;
  std::vector<int> group_of_object;
  for (int64_t i = 0; i < n; ++i) {
    if (!hits.hit(i)) continue;
    const float value = frame.at<float>(static_cast<int>(px[2 * i + 1]),
                                        static_cast<int>(px[2 * i]));
    if (!(value >= o.min_intensity && value <= o.max_intensity)) continue;
    const Eigen::Vector3f p = hits.point(i), nrm = hits.normal(i);
    const Eigen::Vector3f view = (eye - p).normalized();
    if (nrm.dot(view) < 0.08f) continue;  // grazing: mixed pixels
    const int32_t id = hits.object_id[i];
    if (id >= static_cast<int32_t>(group_of_object.size())) {
      group_of_object.resize(id + 1, -1);
    }
    if (group_of_object[id] < 0) {
      group_of_object[id] = s.num_groups++;
      s.group_object.push_back(id);
    }
    s.pixel.emplace_back(px[2 * i], px[2 * i + 1]);
    const Eigen::Vector3f origin = p + offset * nrm;
    s.origin.insert(s.origin.end(), {origin.x(), origin.y(), origin.z()});
    s.normal.push_back(nrm);
    s.intensity.push_back(value);
    s.group.push_back(o.per_object_albedo ? group_of_object[id] : 0);
  }
  if (!o.per_object_albedo) s.num_groups = s.size() > 0 ? 1 : 0;
  return s;
}

// kDefault's objective for one Sun direction: shading = max(0, N.L) x
// visibility, then per group a robust fit of I = A + S shading (A, S >= 0:
// A = albedo x ambient, S = albedo x sun), by iteratively reweighted least
// squares with Cauchy weights. Returns the total Cauchy cost.
class DirectionCost {
 public:
  DirectionCost(const Scene& scene, const Samples& s, double loss_scale)
      : scene_(scene),
        s_(s),
        scale_(loss_scale),
        occluded_(s.size()),
        shading_(s.size()) {}

  double operator()(const Eigen::Vector3d& toward_sun) {
    ++evaluations_;
    const Eigen::Vector3f d = toward_sun.cast<float>();
    scene_.OccludedToward(s_.size(), s_.origin.data(), d, 0.f,
                          std::numeric_limits<float>::infinity(),
                          occluded_.data());
    for (int i = 0; i < s_.size(); ++i) {
      shading_[i] = occluded_[i] ? 0.f : std::max(0.f, s_.normal[i].dot(d));
    }
    RobustAffineFit(s_.size(), shading_.data(), s_.intensity.data(),
                    s_.group.data(), s_.num_groups, scale_, 4, &fit_);
    return fit_.cost;
  }

  const std::vector<float>& shading() const { return shading_; }
  int evaluations() const { return evaluations_; }

 private:
  const Scene& scene_;
  const Samples& s_;
  const double scale_;
  std::vector<uint8_t> occluded_;
  std::vector<float> shading_;
  AffineFit fit_;
  int evaluations_ = 0;
};

struct Evaluated {
  Eigen::Vector3d dir;
  double cost;
};

// Compass search on the sphere around `start`, in its tangent plane: the
// visibility term makes the objective piecewise constant in the direction,
// so a derivative-free search is the honest tool here.
Evaluated RefineDirection(const Evaluated& start, double step_deg,
                          const InitialSunOptions& o, DirectionCost& cost,
                          std::vector<Evaluated>* seen) {
  const double zmin = std::cos(o.max_zenith_deg * kDeg);
  Eigen::Vector3d e1 = start.dir.cross(Eigen::Vector3d::UnitZ());
  if (e1.norm() < 1e-6) e1 = Eigen::Vector3d::UnitX();
  e1.normalize();
  const Eigen::Vector3d e2 = start.dir.cross(e1).normalized();
  Eigen::Vector2d uv(0, 0);
  Evaluated best = start;
  double h = step_deg * kDeg;
  const double tol = o.refine_tolerance_deg * kDeg;
  const Eigen::Vector2d moves[8] = {{1, 0}, {-1, 0},  {0, 1},  {0, -1},
                                    {1, 1}, {-1, -1}, {1, -1}, {-1, 1}};
  int guard = 0;
  while (h > tol && guard++ < 200) {
    Evaluated step_best = best;
    Eigen::Vector2d step_uv = uv;
    for (const auto& m : moves) {
      const Eigen::Vector2d cand = uv + h * m.normalized();
      const Eigen::Vector3d d =
          (start.dir + cand.x() * e1 + cand.y() * e2).normalized();
      if (d.z() < zmin) continue;
      const double c = cost(d);
      seen->push_back({d, c});
      if (c < step_best.cost) {
        step_best = {d, c};
        step_uv = cand;
      }
    }
    if (step_best.cost < best.cost) {
      best = step_best;
      uv = step_uv;
    } else {
      h *= 0.5;
    }
  }
  return best;
}

void Report(const ProgressCallback& progress, double fraction) {
  if (progress && !progress(fraction)) throw Cancelled{};
}

// Inlier statistics and RMS of the final residuals.
void ResidualStats(const std::vector<double>& r, double loss_scale,
                   InitialSunResult* out) {
  double sum2 = 0;
  int inliers = 0;
  for (double v : r) {
    if (std::abs(v) < 3 * loss_scale) {
      sum2 += v * v;
      ++inliers;
    }
  }
  out->inlier_fraction =
      r.empty() ? 0.0 : static_cast<double>(inliers) / r.size();
  out->residual_rms = inliers > 0 ? std::sqrt(sum2 / inliers) : 0.0;
}

// The small dense problems here (a few parameters, thousands of residuals).
void SolveSmall(ceres::Problem* problem, int max_iterations) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.num_threads = 2;
  ceres::Solver::Summary summary;
  ceres::Solve(so, problem, &summary);
}

// Final robust Lambertian fit with the direction fixed: I = rho_o (a + s sh).
// rho of the object with most pixels is held at 1 (the scale ambiguity).
class AlbedoShadingResidual : public ceres::SizedCostFunction<1, 1, 2> {
 public:
  AlbedoShadingResidual(double intensity, double shading)
      : y_(intensity), x_(shading) {}
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    const double rho = p[0][0], a = p[1][0], s = p[1][1];
    r[0] = y_ - rho * (a + s * x_);
    if (J) {
      if (J[0]) J[0][0] = -(a + s * x_);
      if (J[1]) {
        J[1][0] = -rho;
        J[1][1] = -rho * x_;
      }
    }
    return true;
  }

 private:
  double y_, x_;
};

void FitIntensities(const Samples& s, const std::vector<float>& shading,
                    double loss_scale, const InitialSunOptions& o,
                    int num_objects, InitialSunResult* out) {
  std::vector<int> count(s.num_groups, 0);
  for (int g : s.group) ++count[g];
  const int ref = static_cast<int>(
      std::max_element(count.begin(), count.end()) - count.begin());
  std::vector<double> rho(s.num_groups, 1.0);
  double light[2] = {0.05, 0.5};
  ceres::Problem problem;
  for (int i = 0; i < s.size(); ++i) {
    problem.AddResidualBlock(
        new AlbedoShadingResidual(s.intensity[i], shading[i]),
        new ceres::CauchyLoss(loss_scale), &rho[s.group[i]], light);
  }
  for (int g = 0; g < s.num_groups; ++g) {
    problem.SetParameterLowerBound(&rho[g], 0, 1e-4);
  }
  problem.SetParameterBlockConstant(&rho[ref]);
  problem.SetParameterLowerBound(light, 0, 0.0);
  problem.SetParameterLowerBound(light, 1, 0.0);
  SolveSmall(&problem, 50);
  out->ambient_intensity = light[0];
  out->sun_intensity = light[1];
  out->albedo_per_object.assign(num_objects, 1.0);
  if (o.per_object_albedo) {
    for (int g = 0; g < s.num_groups; ++g) {
      if (s.group_object[g] < num_objects)
        out->albedo_per_object[s.group_object[g]] = rho[g];
    }
  }
  std::vector<double> r(s.size());
  for (int i = 0; i < s.size(); ++i) {
    r[i] =
        s.intensity[i] - rho[s.group[i]] * (light[0] + light[1] * shading[i]);
  }
  ResidualStats(r, loss_scale, out);
}

void EstimateDefault(const Scene& scene, const Samples& s,
                     const InitialSunOptions& o,
                     const ProgressCallback& progress, int num_objects,
                     InitialSunResult* out) {
  DirectionCost cost(scene, s, out->loss_scale_abs);
  const auto candidates = FibonacciSky(o.num_candidates, o.max_zenith_deg);
  std::vector<Evaluated> seen;
  seen.reserve(candidates.size() * 4);
  for (size_t k = 0; k < candidates.size(); ++k) {
    seen.push_back({candidates[k], cost(candidates[k])});
    if (k % 16 == 0) Report(progress, 0.5 * k / candidates.size());
  }
  // Spacing of the candidate grid: sqrt(solid angle per candidate).
  const double spacing_deg =
      std::sqrt(2 * M_PI * (1 - std::cos(o.max_zenith_deg * kDeg)) /
                o.num_candidates) /
      kDeg;
  std::vector<Evaluated> order = seen;
  std::sort(
      order.begin(), order.end(),
      [](const Evaluated& a, const Evaluated& b) { return a.cost < b.cost; });
  std::vector<Evaluated> starts;
  for (const auto& e : order) {
    bool far = true;
    for (const auto& st : starts)
      far &= AngleBetweenDeg(st.dir, e.dir) > 2.5 * spacing_deg;
    if (far) starts.push_back(e);
    if (static_cast<int>(starts.size()) >= o.num_refine_starts) break;
  }
  Evaluated best = order.front();
  for (size_t k = 0; k < starts.size(); ++k) {
    const Evaluated refined =
        RefineDirection(starts[k], spacing_deg, o, cost, &seen);
    if (refined.cost < best.cost) best = refined;
    Report(progress, 0.5 + 0.4 * (k + 1) / starts.size());
  }
  // Spread: the widest angle from the best among directions nearly as good.
  const double threshold = best.cost * 1.005 + 1.0;
  double spread = 0;
  for (const auto& e : seen) {
    if (e.cost <= threshold)
      spread = std::max(spread, AngleBetweenDeg(e.dir, best.dir));
  }
  cost(best.dir);  // leaves the shading of the best direction in `cost`
  FitIntensities(s, cost.shading(), out->loss_scale_abs, o, num_objects, out);
  out->sun_in_world = best.dir;
  out->spread_deg = spread;
  out->confidence = out->inlier_fraction * std::exp(-spread / 5.0);

  int lit = 0, shadowed = 0;
  for (int i = 0; i < s.size(); ++i) {
    if (s.normal[i].cast<double>().dot(best.dir) > 0) {
      (cost.shading()[i] > 0 ? lit : shadowed)++;
    }
  }
  if (shadowed < std::max(5, s.size() / 500)) {
    out->message =
        "no cast shadow is visible toward the estimated Sun: the "
        "azimuth rests on shading alone";
    out->confidence *= 0.5;
  }
  if (spread > 20.0) {
    out->message = "the Sun is poorly determined by this frame (directions " +
                   std::to_string(static_cast<int>(spread)) +
                   " deg apart fit about as well)";
  }
}

// Thesis §3.3 residual: S_j - (Ia + sum_i Ii c_ij), intensities >= 0.
class ThesisResidual : public ceres::CostFunction {
 public:
  ThesisResidual(double intensity, std::vector<double> coefficients)
      : y_(intensity), c_(std::move(coefficients)) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(static_cast<int>(c_.size()) + 1);
  }
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    double model = p[0][0];
    for (size_t k = 0; k < c_.size(); ++k) model += p[0][k + 1] * c_[k];
    r[0] = y_ - model;
    if (J && J[0]) {
      J[0][0] = -1.0;
      for (size_t k = 0; k < c_.size(); ++k) J[0][k + 1] = -c_[k];
    }
    return true;
  }

 private:
  double y_;
  std::vector<double> c_;
};

void EstimateThesis(const Scene& scene, const Samples& s,
                    const InitialSunOptions& o,
                    const ProgressCallback& progress, InitialSunResult* out) {
  const Eigen::AlignedBox3f b = scene.bounds();
  const Eigen::Vector3d center = b.center().cast<double>();
  const double radius =
      std::max(1e-3, 0.5 * static_cast<double>(b.diagonal().norm()));
  const int K = o.thesis_num_lights;
  const double light_zenith_deg = 90.0 - o.thesis_light_elevation_deg;
  std::vector<Eigen::Vector3d> light_dir(K), light_pos(K);
  for (int k = 0; k < K; ++k) {
    light_dir[k] = SunInWorldFromAngles(light_zenith_deg, 360.0 * k / K);
    light_pos[k] = center + radius * light_dir[k];
  }
  // Per pixel and light: max(0, L.N) if the light reaches the point.
  const int n = s.size();
  std::vector<std::vector<double>> coef(n, std::vector<double>(K, 0.0));
  std::vector<float> dirs(3 * n);
  std::vector<uint8_t> occluded(n);
  for (int k = 0; k < K; ++k) {
    float t_far = std::numeric_limits<float>::infinity();
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d p(s.origin[3 * i], s.origin[3 * i + 1],
                              s.origin[3 * i + 2]);
      const Eigen::Vector3d v = light_pos[k] - p;
      for (int c = 0; c < 3; ++c) dirs[3 * i + c] = static_cast<float>(v[c]);
    }
    // The lights sit on the sphere that encloses the model's bounds, so
    // nothing lies beyond them: an unbounded ray toward the light is exact.
    scene.Occluded(n, s.origin.data(), dirs.data(), 0.f, t_far,
                   occluded.data());
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d v(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2]);
      coef[i][k] =
          occluded[i]
              ? 0.0
              : std::max(0.0, s.normal[i].cast<double>().dot(v.normalized()));
    }
    Report(progress, 0.6 * (k + 1) / K);
  }
  std::vector<double> x(K + 1, 0.1);
  ceres::Problem problem;
  for (int i = 0; i < n; ++i) {
    problem.AddResidualBlock(new ThesisResidual(s.intensity[i], coef[i]),
                             nullptr, x.data());
  }
  for (int k = 0; k <= K; ++k) problem.SetParameterLowerBound(x.data(), k, 0.0);
  SolveSmall(&problem, 100);
  Report(progress, 0.95);

  Eigen::Vector3d centre_of_intensity = Eigen::Vector3d::Zero();
  double total = 0;
  for (int k = 0; k < K; ++k) {
    centre_of_intensity += x[k + 1] * light_dir[k];
    total += x[k + 1];
  }
  out->light_intensities.assign(x.begin() + 1, x.end());
  out->ambient_intensity = x[0];
  out->sun_intensity = total;
  if (!(total > 0) || centre_of_intensity.norm() < 1e-12) {
    out->status = InitialSunResult::Status::kNoLight;
    out->message = "no light explains the image (all fitted intensities are 0)";
    return;
  }
  out->sun_in_world = centre_of_intensity.normalized();
  std::vector<double> r(n);
  for (int i = 0; i < n; ++i) {
    double model = x[0];
    for (int k = 0; k < K; ++k) model += x[k + 1] * coef[i][k];
    r[i] = s.intensity[i] - model;
  }
  ResidualStats(r, out->loss_scale_abs, out);
  out->spread_deg =
      std::numeric_limits<double>::quiet_NaN();  // thesis gives none
  out->confidence = out->inlier_fraction;
}

}  // namespace

void InitialSunOptions::Check() const {
  Require(max_pixels >= 100, "max_pixels must be >= 100");
  Require(ignore_top_rows >= 0 && ignore_bottom_rows >= 0,
          "ignore_top_rows/ignore_bottom_rows must be >= 0");
  Require(min_intensity >= 0 && max_intensity > min_intensity &&
              max_intensity <= 1.0,
          "need 0 <= min_intensity < max_intensity <= 1");
  Require(thesis_num_lights >= 1 && thesis_num_lights <= 256,
          "thesis_num_lights must be in [1, 256]");
  Require(thesis_light_elevation_deg > 0 && thesis_light_elevation_deg <= 90,
          "thesis_light_elevation_deg must be in (0, 90]");
  Require(num_candidates >= 8 && num_candidates <= 100000,
          "num_candidates must be in [8, 100000]");
  Require(num_refine_starts >= 1, "num_refine_starts must be >= 1");
  Require(refine_tolerance_deg > 0, "refine_tolerance_deg must be > 0");
  Require(loss_scale > 0, "loss_scale must be > 0");
  Require(max_zenith_deg > 0 && max_zenith_deg <= 90,
          "max_zenith_deg must be in (0, 90]");
}

InitialSunResult EstimateInitialSun(const Scene& scene, const Camera& camera,
                                    const cv::Mat& frame,
                                    const InitialSunOptions& options,
                                    const ProgressCallback& progress) {
  options.Check();
  Require(!frame.empty(), "frame: empty image");
  Require(frame.type() == CV_32FC1,
          "frame: expected a single-channel float32 image");
  Require(frame.cols == camera.width() && frame.rows == camera.height(),
          "frame: size " + std::to_string(frame.cols) + "x" +
              std::to_string(frame.rows) + " differs from the camera's " +
              std::to_string(camera.width()) + "x" +
              std::to_string(camera.height()));
  Require(options.ignore_top_rows + options.ignore_bottom_rows < frame.rows,
          "ignore_top_rows + ignore_bottom_rows leave no rows");
  const auto t0 = std::chrono::steady_clock::now();
  InitialSunResult out;
  try {
    const Samples s = GatherSamples(scene, camera, frame, options);
    out.num_pixels = s.size();
    if (s.size() < 50) {
      out.message =
          "too few usable pixels see the model (" + std::to_string(s.size()) +
          "): check that the camera is matched to the footage and the model "
          "is in view";
      return out;
    }
    int num_objects = 0;
    for (int64_t t = 0; t < scene.num_triangles(); ++t) {
      num_objects = std::max(num_objects, scene.object_id_of_triangle(t) + 1);
    }
    std::vector<float> sorted = s.intensity;
    out.loss_scale_abs =
        std::max(1e-4, options.loss_scale * MedianInPlace(&sorted));
    out.status = InitialSunResult::Status::kSuccess;
    if (options.method == InitialSunMethod::kThesis) {
      EstimateThesis(scene, s, options, progress, &out);
    } else {
      EstimateDefault(scene, s, options, progress, num_objects, &out);
    }
    AnglesFromSunInWorld(out.sun_in_world, &out.zenith_deg, &out.azimuth_deg);
    Report(progress, 1.0);
  } catch (const Cancelled&) {
    out = InitialSunResult();
    out.status = InitialSunResult::Status::kCancelled;
    out.message = "cancelled";
  }
  out.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  return out;
}

}  // namespace sunlapse
