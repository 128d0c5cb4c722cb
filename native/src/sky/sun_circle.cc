#include "sunlapse/sky/sun_circle.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <tuple>

#include "sunlapse/common/angles.h"
#include "sunlapse/common/order_statistics.h"
#include "sunlapse/common/require.h"

namespace sunlapse {
namespace {

using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The Sun's hour angle advances 15 deg per hour of (mean) solar time.
constexpr double kDegPerHour = 15.0;

struct Basis {
  Vector3d p, e1, e2;
};

// The pole p and the circle's plane's axes: e1 along the pole's meridian
// toward the zenith side (hour angle 0 = noon, the Sun's highest point), e2 =
// p x e1 east, so the angle from e1 toward e2 is minus the (westward) hour
// angle. up - (up.p) p is sin(pz) (-cz sa, -cz ca, sz): e1 is that unit
// vector times the sign of sin(pz), and e2 (ca, -sa, 0) times it.
Basis PoleBasis(double pole_zenith, double pole_azimuth) {
  const double sz = std::sin(pole_zenith), cz = std::cos(pole_zenith);
  const double sa = std::sin(pole_azimuth), ca = std::cos(pole_azimuth);
  Basis b;
  b.p = {sz * sa, sz * ca, cz};
  if (std::abs(sz) <= 1e-9) {
    b.e1 = {1.0, 0.0, 0.0};
    b.e2 = b.p.cross(b.e1);
    return b;
  }
  const double sign = sz > 0 ? 1.0 : -1.0;
  b.e1 = {-sign * cz * sa, -sign * cz * ca, std::abs(sz)};
  b.e2 = {sign * ca, -sign * sa, 0.0};
  return b;
}

Vector3d OnCircle(const Basis& b, double declination, double h) {
  return std::cos(declination) * (std::cos(h) * b.e1 + std::sin(h) * b.e2) +
         std::sin(declination) * b.p;
}

// The circle's parameters: pole zenith and azimuth, declination, the angle
// about the pole at t = 0 (radians) and, when fitted, its rate per time unit.
struct Circle {
  VectorXd params;
  double fixed_rate = kNaN;  // the rate when times are seconds
  // The rate of `trial` parameters (the fitted one, or the fixed one).
  double RateOf(const VectorXd& trial) const {
    return std::isnan(fixed_rate) ? trial[4] : fixed_rate;
  }
  // The Sun on the circle of `trial` parameters at each time.
  std::vector<Vector3d> SunsAt(const VectorXd& trial,
                               const std::vector<double>& t) const {
    const Basis b = PoleBasis(trial[0], trial[1]);
    const double rate = RateOf(trial);
    std::vector<Vector3d> out(t.size());
    for (size_t i = 0; i < t.size(); ++i)
      out[i] = OnCircle(b, trial[2], trial[3] + rate * t[i]);
    return out;
  }
};

// The measured Suns and what the fit weighs them by.
struct Measured {
  std::vector<double> t;
  std::vector<Vector3d> sun;
  std::vector<double> w;
};

VectorXd Residuals(const Circle& c, const VectorXd& params, const Measured& m,
                   const std::vector<double>& robust) {
  const std::vector<Vector3d> suns = c.SunsAt(params, m.t);
  VectorXd r(3 * m.t.size());
  for (size_t i = 0; i < m.t.size(); ++i) {
    r.segment<3>(3 * i) = (suns[i] - m.sun[i]) * std::sqrt(m.w[i] * robust[i]);
  }
  return r;
}

// The residuals' derivatives by each parameter. Analytic: the forward
// differences cost five evaluations of the model an iteration. Numeric where
// the pole is at the zenith (the basis jumps there).
MatrixXd Jacobian(const Circle& c, const VectorXd& params, const Measured& m,
                  const std::vector<double>& robust, const VectorXd& r0) {
  const int np = static_cast<int>(params.size());
  MatrixXd jac(3 * m.t.size(), np);
  const double pz = params[0], pa = params[1], dec = params[2];
  const double sz = std::sin(pz), cz = std::cos(pz);
  if (std::abs(sz) <= 1e-9) {
    for (int k = 0; k < np; ++k) {
      VectorXd moved = params;
      moved[k] += 1e-6;
      jac.col(k) = (Residuals(c, moved, m, robust) - r0) / 1e-6;
    }
    return jac;
  }
  const double sa = std::sin(pa), ca = std::cos(pa);
  const double sign = sz > 0 ? 1.0 : -1.0;
  const Basis b = PoleBasis(pz, pa);
  const double cd = std::cos(dec), sd = std::sin(dec);
  const double rate = c.RateOf(params);
  // d e1/d pz = sign p, d e2/d pz = 0, d p/d pz = -sign e1;
  // d e1/d pa = sign (-cz ca, cz sa, 0), d e2/d pa = sign (-sa, -ca, 0),
  // d p/d pa = sz (ca, -sa, 0).
  const Vector3d de1_pa(-cz * ca, cz * sa, 0.0), de2_pa(-sa, -ca, 0.0);
  const Vector3d dp_pa(ca, -sa, 0.0);
  for (size_t i = 0; i < m.t.size(); ++i) {
    const double root_w = std::sqrt(m.w[i] * robust[i]);
    const double h = params[3] + rate * m.t[i];
    const double ch = std::cos(h), sh = std::sin(h);
    const Vector3d along = ch * b.e1 + sh * b.e2;
    const Vector3d ahead = cd * (ch * b.e2 - sh * b.e1);
    const auto rows = [&](int k) { return jac.block<3, 1>(3 * i, k); };
    rows(0) = (cd * sign * ch * b.p - sd * sign * b.e1) * root_w;
    rows(1) =
        (cd * sign * (ch * de1_pa + sh * de2_pa) + sd * sz * dp_pa) * root_w;
    rows(2) = (-sd * along + cd * b.p) * root_w;
    rows(3) = ahead * root_w;
    if (np == 5) rows(4) = ahead * (m.t[i] * root_w);
  }
  return jac;
}

// The Levenberg-Marquardt step. The damped normal matrix is positive
// definite but for a degenerate fit, which gets the least-squares step.
VectorXd DampedStep(const MatrixXd& jtj, const VectorXd& jtr, double lam) {
  MatrixXd damped = jtj;
  damped.diagonal() += lam * (jtj.diagonal().array() + 1e-9).matrix();
  Eigen::FullPivLU<MatrixXd> lu(damped);
  if (lu.isInvertible()) return lu.solve(-jtr);
  return damped.completeOrthogonalDecomposition().solve(-jtr);
}

// numpy's unwrap: each step taken the shorter way round.
std::vector<double> Unwrap(const std::vector<double>& angles) {
  std::vector<double> out(angles);
  double correction = 0.0;
  for (size_t i = 1; i < angles.size(); ++i) {
    const double d = angles[i] - angles[i - 1];
    double wrapped =
        std::fmod(std::fmod(d + M_PI, 2 * M_PI) + 2 * M_PI, 2 * M_PI) - M_PI;
    if (wrapped == -M_PI && d > 0) wrapped = M_PI;
    if (std::abs(d) >= M_PI) correction += wrapped - d;
    out[i] = angles[i] + correction;
  }
  return out;
}

double Median(std::vector<double> v) { return MedianInPlace(&v); }

}  // namespace

void SunCircleOptions::Check() const {
  Require(iterations >= 1, "iterations must be >= 1");
  Require(reweight_every >= 1, "reweight_every must be >= 1");
  Require(settled_step_rad >= 0 && std::isfinite(settled_step_rad),
          "settled_step_rad must be >= 0");
  Require(settled_weight >= 0 && std::isfinite(settled_weight),
          "settled_weight must be >= 0");
}

void TrimmedCircleOptions::Check() const {
  Require(inlier_medians > 0 && std::isfinite(inlier_medians),
          "inlier_medians must be > 0");
  Require(rounds >= 1, "rounds must be >= 1");
  Require(round_iterations >= 1, "round_iterations must be >= 1");
  Require(min_frames >= 4,
          "min_frames must be >= 4 (a circle has 5 "
          "parameters, 4 with known times)");
  Require(max_fit_frames >= min_frames, "max_fit_frames must be >= min_frames");
  Require(min_inlier_share > 0 && min_inlier_share <= 1,
          "min_inlier_share must be in (0, 1]");
}

SunCircleFit FitSunCircle(const std::vector<double>& times,
                          const std::vector<Vector3d>& suns_in_world,
                          const std::vector<double>& weights,
                          const SunCircleOptions& options) {
  options.Check();
  const size_t n = times.size();
  Require(suns_in_world.size() == n, "suns_in_world: expected one per time (" +
                                         std::to_string(n) + "), got " +
                                         std::to_string(suns_in_world.size()));
  Require(weights.empty() || weights.size() == n,
          "weights: expected none or one per time (" + std::to_string(n) +
              "), got " + std::to_string(weights.size()));
  SunCircleFit out;
  std::vector<size_t> ok;
  for (size_t i = 0; i < n; ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    // A weight that is not a finite positive number leaves its Sun out (an
    // infinite one made the whole fit NaN).
    if (suns_in_world[i].allFinite() && suns_in_world[i].norm() > 0 &&
        std::isfinite(times[i]) && std::isfinite(w) && w > 0) {
      ok.push_back(i);
    }
  }
  if (ok.size() < 4) {
    out.status = SunCircleFit::Status::kTooFewSuns;
    out.message = "needs at least 4 measured frames (has " +
                  std::to_string(ok.size()) + ")";
    return out;
  }
  std::vector<double> ok_times;
  for (size_t i : ok) ok_times.push_back(times[i]);
  const double t0 = Median(ok_times);
  const double scale = options.times_are_seconds ? 3600.0 : 1.0;
  Measured m;
  for (size_t i : ok) {
    m.t.push_back((times[i] - t0) / scale);
    m.sun.push_back(suns_in_world[i].normalized());
    m.w.push_back(weights.empty() ? 1.0 : weights[i]);
  }
  const auto [t_min, t_max] = std::minmax_element(m.t.begin(), m.t.end());
  if (!(*t_max > *t_min)) {
    out.status = SunCircleFit::Status::kSameTimes;
    out.message = "the measured frames all have the same time";
    return out;
  }
  const size_t k = m.t.size();
  // Start: the plane through the measured Suns; its normal is the pole.
  Vector3d centre = Vector3d::Zero();
  double w_sum = 0.0;
  for (size_t i = 0; i < k; ++i) {
    centre += m.w[i] * m.sun[i];
    w_sum += m.w[i];
  }
  centre /= w_sum;
  MatrixXd spread(k, 3);
  for (size_t i = 0; i < k; ++i) {
    spread.row(i) = (m.sun[i] - centre).transpose() * std::sqrt(m.w[i]);
  }
  Vector3d p =
      Eigen::JacobiSVD<MatrixXd>(spread, Eigen::ComputeThinV).matrixV().col(2);
  // The Sun turns westward: clockwise about the north celestial pole.
  double turn = 0.0;
  for (size_t i = 0; i + 1 < k; ++i) {
    const double dt = m.t[i + 1] - m.t[i];
    turn += m.sun[i].cross(m.sun[i + 1]).dot(p) *
            static_cast<double>((dt > 0) - (dt < 0));
  }
  if (turn > 0) p = -p;
  Circle c;
  if (options.times_are_seconds) c.fixed_rate = -kDegPerHour * kRadPerDeg;
  const double pz = std::acos(std::clamp(p.z(), -1.0, 1.0));
  const double pa = std::atan2(p.x(), p.y());
  const double dec = std::asin(
      std::clamp(centre.dot(p) / std::max(1e-9, centre.norm()), -1.0, 1.0));
  const Basis start = PoleBasis(pz, pa);
  std::vector<double> about(k);
  for (size_t i = 0; i < k; ++i) {
    about[i] = std::atan2(m.sun[i].dot(start.e2), m.sun[i].dot(start.e1));
  }
  about = Unwrap(about);
  double rate = c.fixed_rate;
  if (std::isnan(rate)) {
    double tm = 0.0, hm = 0.0;
    for (size_t i = 0; i < k; ++i) {
      tm += m.t[i] / k;
      hm += about[i] / k;
    }
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < k; ++i) {
      num += (m.t[i] - tm) * (about[i] - hm);
      den += (m.t[i] - tm) * (m.t[i] - tm);
    }
    rate = num / den;
  }
  std::vector<double> h0(k);
  for (size_t i = 0; i < k; ++i) h0[i] = about[i] - rate * m.t[i];
  c.params.resize(std::isnan(c.fixed_rate) ? 5 : 4);
  c.params.head<4>() << pz, pa, dec, Median(h0);
  if (c.params.size() == 5) c.params[4] = rate;

  std::vector<double> robust(k, 1.0);
  double lam = 1e-3;
  // The residuals and the Jacobian at the current parameters, kept while
  // they hold: an accepted step's residuals are the next iteration's, and a
  // rejected step leaves both as they were.
  VectorXd r0;
  MatrixXd jac;
  bool have_r0 = false, have_jac = false;
  // Settled: the last step moved no parameter by settled_step_rad; the
  // steps until the next robust weights would not move them either, so they
  // are skipped, and the fit ends when those weights hold too.
  bool settled = false;
  const auto angles_off = [&](const VectorXd& params) {
    const std::vector<Vector3d> suns = c.SunsAt(params, m.t);
    std::vector<double> ang(k);
    for (size_t i = 0; i < k; ++i) {
      // The chord in degrees-per-radian units (small-angle: the angle).
      ang[i] = (suns[i] - m.sun[i]).norm() / kRadPerDeg;
    }
    return ang;
  };
  for (int it = 0; it < options.iterations; ++it) {
    if (!settled) {
      if (!have_r0) {
        r0 = Residuals(c, c.params, m, robust);
        have_r0 = true;
      }
      if (!have_jac) {
        jac = Jacobian(c, c.params, m, robust, r0);
        have_jac = true;
      }
      const VectorXd step =
          DampedStep(jac.transpose() * jac, jac.transpose() * r0, lam);
      const VectorXd trial = c.params + step;
      VectorXd r1 = Residuals(c, trial, m, robust);
      if (r1.squaredNorm() < r0.squaredNorm()) {
        c.params = trial;
        lam *= 0.3;
        r0 = std::move(r1);
        have_jac = false;
      } else {
        lam *= 10.0;
      }
      settled = step.cwiseAbs().maxCoeff() < options.settled_step_rad;
    }
    if (it % options.reweight_every == options.reweight_every - 1) {
      // Huber weights on the angle.
      const std::vector<double> ang = angles_off(c.params);
      const double huber = 1.5 * (1.4826 * Median(ang) + 1e-3);
      double change = 0.0;
      std::vector<double> now(k);
      for (size_t i = 0; i < k; ++i) {
        now[i] = ang[i] <= huber ? 1.0 : huber / std::max(ang[i], 1e-12);
        change = std::max(change, std::abs(now[i] - robust[i]));
      }
      if (settled && change < options.settled_weight) break;
      robust = std::move(now);
      have_r0 = have_jac = settled = false;
    }
  }
  const Basis b = PoleBasis(c.params[0], c.params[1]);
  const double r = c.RateOf(c.params);
  out.status = SunCircleFit::Status::kSuccess;
  out.latitude_deg = std::asin(std::clamp(b.p.z(), -1.0, 1.0)) / kRadPerDeg;
  out.declination_deg = c.params[2] / kRadPerDeg;
  double pole_zenith_deg = 0.0;
  AnglesFromSunInWorld(b.p, &pole_zenith_deg, &out.north_offset_deg);
  out.sun_in_world.reserve(n);
  out.hour_angle_deg.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const double h = c.params[3] + r * (times[i] - t0) / scale;
    out.sun_in_world.push_back(OnCircle(b, c.params[2], h));
    out.hour_angle_deg.push_back(WrapAzimuthDeg(-h / kRadPerDeg + 180.0) -
                                 180.0);
  }
  out.residual_deg = Median(angles_off(c.params));
  out.rate_deg = -r / kRadPerDeg / scale;
  if (std::abs(out.latitude_deg) > 89.0) {
    out.message =
        "the pole is near the zenith: the fit cannot tell latitude from the "
        "path";
  }
  return out;
}

SunCircleFit FitTrimmedSunCircle(const std::vector<double>& times,
                                 const std::vector<Vector3d>& suns_in_world,
                                 const std::vector<double>& weights,
                                 double floor_deg,
                                 const SunCircleOptions& circle_options,
                                 const TrimmedCircleOptions& options) {
  options.Check();
  circle_options.Check();
  Require(std::isfinite(floor_deg) && floor_deg >= 0, "floor_deg must be >= 0");
  const size_t n = times.size();
  Require(suns_in_world.size() == n, "suns_in_world: expected one per time");
  Require(weights.empty() || weights.size() == n,
          "weights: expected none or one per time");
  SunCircleFit out;
  std::vector<int> given;
  for (size_t i = 0; i < n; ++i) {
    if (suns_in_world[i].allFinite() && suns_in_world[i].norm() > 0) {
      given.push_back(static_cast<int>(i));
    }
  }
  if (static_cast<int>(given.size()) < options.min_frames) {
    out.status = SunCircleFit::Status::kTooFewSuns;
    out.message = "needs at least " + std::to_string(options.min_frames) +
                  " Suns (has " + std::to_string(given.size()) + ")";
    return out;
  }
  // The Suns of the rounds, spread over the segment.
  std::vector<int> use;
  {
    const size_t g = given.size(), want = options.max_fit_frames;
    std::set<size_t> at;
    for (size_t j = 0; j < std::min(g, want); ++j) {
      at.insert(g <= want
                    ? j
                    : static_cast<size_t>(std::nearbyint(
                          static_cast<double>(j) * (g - 1) / (want - 1))));
    }
    for (size_t j : at) use.push_back(given[j]);
  }
  const size_t u = use.size();
  std::vector<double> t_use(u), w_use(u);
  std::vector<Vector3d> s_use(u);
  for (size_t j = 0; j < u; ++j) {
    t_use[j] = times[use[j]];
    s_use[j] = suns_in_world[use[j]].normalized();
    w_use[j] = weights.empty() ? 1.0 : weights[use[j]];
  }
  SunCircleOptions round_options = circle_options;
  round_options.iterations = options.round_iterations;

  // A start's outcome: inliers (positions in `use`, ascending), their
  // median distance (NaN when a fit failed) and every Sun's distance.
  struct Trial {
    std::vector<int> inliers;
    double median = kNaN;
    std::vector<double> off;
  };
  const Vector3d none = Vector3d::Constant(kNaN);
  const auto trim = [&](std::vector<int> inliers) {
    Trial trial;
    for (int round = 0; round < options.rounds; ++round) {
      std::vector<Vector3d> suns(u, none);
      for (int j : inliers) suns[j] = s_use[j];
      const SunCircleFit fit = FitSunCircle(t_use, suns, w_use, round_options);
      if (fit.status != SunCircleFit::Status::kSuccess) {
        trial.median = kNaN;
        break;
      }
      trial.off.resize(u);
      for (size_t j = 0; j < u; ++j) {
        trial.off[j] = AngleBetweenDeg(fit.sun_in_world[j], s_use[j]);
      }
      std::vector<double> in_off;
      for (int j : inliers) in_off.push_back(trial.off[j]);
      trial.median = Median(in_off);
      const double limit =
          std::max(floor_deg, options.inlier_medians * trial.median);
      std::vector<int> keep;
      for (size_t j = 0; j < u; ++j) {
        if (trial.off[j] <= limit) keep.push_back(static_cast<int>(j));
      }
      if (keep == inliers || static_cast<int>(keep.size()) < options.min_frames)
        break;
      inliers = std::move(keep);
    }
    trial.inliers = std::move(inliers);
    return trial;
  };

  std::vector<int> all(u);
  for (size_t j = 0; j < u; ++j) all[j] = static_cast<int>(j);
  std::vector<Trial> tried{trim(all)};
  // (Skipping the halves when every Sun is within a few degrees of the
  // first start's circle kept the bent circles: they hold the wrong Suns
  // within a few degrees, which is how they fail.)
  if (tried[0].inliers.size() < u) {
    const size_t half = u / 2;
    const std::vector<int> first(all.begin(), all.begin() + half);
    const std::vector<int> second(all.begin() + half, all.end());
    for (const std::vector<int>* start : {&first, &second}) {
      if (static_cast<int>(start->size()) >= options.min_frames)
        tried.push_back(trim(*start));
    }
  }
  std::vector<const Trial*> candidates;
  for (const Trial& trial : tried) {
    if (!std::isnan(trial.median) &&
        trial.inliers.size() >= options.min_inlier_share * u) {
      candidates.push_back(&trial);
    }
  }
  if (candidates.empty()) {
    out.status = SunCircleFit::Status::kNoCircle;
    out.message = "no circle holds half the Suns";
    return out;
  }
  // The start whose circle has the most Suns within one limit for all (the
  // tightest start's) wins: a circle bent toward the wrong Suns holds more
  // of them within its own, looser, limit.
  double tightest = candidates[0]->median;
  for (const Trial* trial : candidates)
    tightest = std::min(tightest, trial->median);
  const double limit = std::max(floor_deg, options.inlier_medians * tightest);
  const Trial* best = nullptr;
  std::pair<long, double> best_key;
  for (const Trial* trial : candidates) {
    const long held = std::count_if(trial->off.begin(), trial->off.end(),
                                    [&](double v) { return v <= limit; });
    const std::pair<long, double> key{held, -trial->median};
    if (best == nullptr || key > best_key) best = trial, best_key = key;
  }
  // The circle at every given time, fitted once more on the inliers.
  std::vector<Vector3d> inlier_suns(n, none);
  for (int j : best->inliers) inlier_suns[use[j]] = suns_in_world[use[j]];
  SunCircleFit fit = FitSunCircle(times, inlier_suns, weights, circle_options);
  if (fit.status != SunCircleFit::Status::kSuccess) return fit;
  fit.off_deg.assign(n, kNaN);
  for (int i : given) {
    fit.off_deg[i] = AngleBetweenDeg(fit.sun_in_world[i], suns_in_world[i]);
  }
  std::vector<double> in_off;
  for (int j : best->inliers) {
    fit.inliers.push_back(use[j]);
    in_off.push_back(fit.off_deg[use[j]]);
  }
  fit.residual_deg = Median(in_off);
  return fit;
}

}  // namespace sunlapse
