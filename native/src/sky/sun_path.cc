#include "sunlapse/sky/sun_path.h"
#include "sunlapse/common/require.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace sunlapse {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Frames between the forward pass's checkpoints when it is not kept whole.
constexpr int kCheckpointFrames = 64;

}  // namespace

void SunPathOptions::Check() const {
  Require(evidence_weight > 0 && std::isfinite(evidence_weight),
          "evidence_weight must be > 0");
  Require(step_weight >= 0 && std::isfinite(step_weight),
          "step_weight must be >= 0");
  Require(std::isfinite(jump_cost),
          "jump_cost must be finite (negative: no jumps)");
  Require(max_step_deg > 0 && max_step_deg <= 90,
          "max_step_deg must be in (0, 90]");
  Require(max_speed_deg_per_hour > 0 && max_speed_deg_per_hour <= 90,
          "max_speed_deg_per_hour must be in (0, 90]");
  Require(min_significance >= 0, "min_significance must be >= 0");
  Require(min_margin >= 0 && std::isfinite(min_margin),
          "min_margin must be >= 0");
  Require(rival_exclusion_deg >= 0 && rival_exclusion_deg <= 90,
          "rival_exclusion_deg must be in [0, 90]");
  Require(prior_tolerance_deg >= 0 && std::isfinite(prior_tolerance_deg),
          "prior_tolerance_deg must be >= 0");
  Require(prior_weight >= 0 && std::isfinite(prior_weight),
          "prior_weight must be >= 0");
  Require(prior_max_cost >= 0 && std::isfinite(prior_max_cost),
          "prior_max_cost must be >= 0");
  Require(keep_forward_mb >= 0 && std::isfinite(keep_forward_mb),
          "keep_forward_mb must be >= 0");
}

SunPathResult SolveSunPath(const SkyEvidence& evidence,
                           const std::vector<double>& times_s,
                           const std::vector<uint8_t>& segment_start,
                           const SunPathOptions& o,
                           const std::vector<Eigen::Vector3d>& prior,
                           const std::vector<uint8_t>& ignored) {
  o.Check();
  const int T = evidence.num_frames();
  const SkyGrid& grid = evidence.grid();
  const int D = grid.size();
  Require(times_s.empty() || static_cast<int>(times_s.size()) == T,
          "times_s: one time per frame, or none");
  Require(segment_start.empty() || static_cast<int>(segment_start.size()) == T,
          "segment_start: one flag per frame, or none");
  Require(prior.empty() || static_cast<int>(prior.size()) == T,
          "prior: one direction per frame, or none");
  Require(ignored.empty() || static_cast<int>(ignored.size()) == T,
          "ignored: one flag per frame, or none");
  auto used = [&](int t) { return ignored.empty() || !ignored[t]; };
  SunPathResult out;
  out.direction.assign(T, -1);
  out.jump_before.assign(T, 0);
  out.measured.assign(T, 0);
  out.explained.assign(T, 0.f);
  out.margin.assign(T, 0.f);
  out.significance.assign(T, 0.f);
  out.path_margin.assign(T, 0.f);
  if (T == 0) {
    out.message = "no frames";
    return out;
  }
  const std::vector<uint8_t>& scores = evidence.scores();
  // Each frame's cost of a direction, relative to the frame's best (0 there;
  // 0 everywhere on a frame without evidence, which is then carried).
  auto evidence_cost = [&](int t, int d) {
    return used(t) ? scores[static_cast<size_t>(t) * D + d] / 10.0 : 0.0;
  };
  // The prior's cost of a direction on a frame, in the evidence's units,
  // from its angle to the frame's prior direction (none: no prior there).
  // Computed when asked, not stored: a table of frames x directions would
  // make the solve's memory grow with the clip (120 MB at 10,000 frames).
  std::vector<Eigen::Vector3d> prior_unit(prior.empty() ? 0 : T,
                                          Eigen::Vector3d::Zero());
  for (int t = 0; t < static_cast<int>(prior_unit.size()); ++t) {
    if (prior[t].allFinite() && prior[t].norm() >= 0.5)
      prior_unit[t] = prior[t].normalized();
  }
  // Within prior_tolerance_deg the prior costs nothing, and beyond the
  // angle where it reaches prior_max_cost it costs that: only the ring
  // between needs the angle (a margin of 1e-9 rad keeps both bounds on
  // their side; the acos for every direction of every frame, three times,
  // was a quarter of a solve with a prior).
  const double cos_free = std::cos(o.prior_tolerance_deg * kDeg - 1e-9);
  const double capped_deg =
      o.prior_weight > 0
          ? o.prior_tolerance_deg + std::sqrt(o.prior_max_cost / o.prior_weight)
          : kInf;
  const double cos_capped =
      capped_deg < 180.0 ? std::cos(capped_deg * kDeg + 1e-9) : -2.0;
  auto cost_of = [&](int t, int d) {
    const double c = evidence_cost(t, d);
    if (prior_unit.empty() || prior_unit[t].isZero()) return c;
    const double cos_off = grid.direction(d).dot(prior_unit[t]);
    if (cos_off >= cos_free) return c;
    if (cos_off < cos_capped) return c + o.prior_max_cost;
    const double off = std::acos(std::clamp(cos_off, -1.0, 1.0)) / kDeg -
                       o.prior_tolerance_deg;
    return off <= 0
               ? c
               : c + std::min(o.prior_max_cost, o.prior_weight * off * off);
  };
  bool any = false;
  for (int t = 0; t < T && !any; ++t)
    any = used(t) && evidence.Significance(t) > 0.0;
  if (!any) {
    out.status = SunPathResult::Status::kNoEvidence;
    out.message = "no frame shows shadows the model can cast";
    return out;
  }
  const double slack = 2.0 * grid.spacing_deg();
  auto radius = [&](int t) {  // allowed motion from frame t-1 to t (deg)
    const double dt = times_s.empty() ? NAN : times_s[t] - times_s[t - 1];
    if (std::isfinite(dt))
      return std::abs(dt) / 3600.0 * o.max_speed_deg_per_hour + slack;
    return std::max(o.max_step_deg, slack);
  };

  // The grid's cached neighbours (nearest first) out to the largest step
  // within the cache's radius, in flat arrays: the recursion reads them for
  // every direction of every frame, three times, and the per-direction
  // lists of the grid cost more to walk than the steps themselves. A step
  // beyond the cache (a night between two timed days) scans the grid as
  // before.
  double widest = -1.0;
  for (int t = 1; t < T; ++t) {
    const double r = radius(t);
    if (r <= grid.cached_radius_deg()) widest = std::max(widest, r);
  }
  std::vector<int64_t> near_first(widest >= 0 ? D + 1 : 0, 0);
  std::vector<int32_t> near_index;
  std::vector<float> near_angle;
  if (widest >= 0) {
    for (int d = 0; d < D; ++d) {
      for (const SkyGrid::Neighbour& nb : grid.Cached(d)) {
        if (nb.angle_deg > widest) break;
        near_index.push_back(nb.index);
        near_angle.push_back(nb.angle_deg);
      }
      near_first[d + 1] = static_cast<int64_t>(near_index.size());
    }
  }

  // One step of the recursion between frame t-1 and frame t (symmetric, so
  // it serves both directions): out[d] = min over p of in[p] + the step's
  // cost, or a jump from the best of `in`, or no step at a segment start.
  auto relax = [&](const std::vector<double>& in, int t,
                   std::vector<double>* out_cost, int* back_row,
                   uint8_t* jumped_row) {
    const bool hard = !segment_start.empty() && segment_start[t];
    const auto best_in = std::min_element(in.begin(), in.end());
    const double in_min = *best_in;
    const int in_arg = static_cast<int>(best_in - in.begin());
    const double r = radius(t);
    const double step_per_deg2 = o.step_weight / (r * r);
    // The cheapest step into d from its neighbours within r: the value
    // alone in four running minima (exact: a minimum does not depend on the
    // order), or with its origin, nearest first as the grid lists them.
    auto best_step = [&](int d, int* arg) {
      const int64_t k0 = near_first[d];
      const int64_t k1 =
          std::upper_bound(
              near_angle.begin() + k0, near_angle.begin() + near_first[d + 1],
              static_cast<float>(r), [r](float, float a) { return a > r; }) -
          near_angle.begin();
      const int32_t* idx = near_index.data();
      const float* ang = near_angle.data();
      auto step = [&](int64_t k) {
        return in[idx[k]] + step_per_deg2 * ang[k] * ang[k];
      };
      double c = kInf;
      if (arg != nullptr) {
        for (int64_t k = k0; k < k1; ++k) {
          const double s = step(k);
          if (s < c) c = s, *arg = idx[k];
        }
        return c;
      }
      double c1 = kInf, c2 = kInf, c3 = kInf;
      int64_t k = k0;
      for (; k + 4 <= k1; k += 4) {
        c = std::min(c, step(k));
        c1 = std::min(c1, step(k + 1));
        c2 = std::min(c2, step(k + 2));
        c3 = std::min(c3, step(k + 3));
      }
      for (; k < k1; ++k) c = std::min(c, step(k));
      return std::min(std::min(c, c1), std::min(c2, c3));
    };
    // Directions are independent: in parallel (the solve is a few ms a
    // frame on long clips, after the pass, with nothing to overlap it).
    tbb::parallel_for(
        tbb::blocked_range<int>(0, D, 128),
        [&](const tbb::blocked_range<int>& range) {
          for (int d = range.begin(); d < range.end(); ++d) {
            double c = kInf;
            int arg = -1;
            bool jump = false;
            if (hard) {
              c = in_min, arg = in_arg;
            } else {
              if (r <= widest) {
                c = best_step(d, back_row ? &arg : nullptr);
              } else {
                for (int p : grid.Within(d, r)) {
                  const double ang =
                      std::acos(
                          std::clamp(grid.direction(p).dot(grid.direction(d)),
                                     -1.0, 1.0)) /
                      kDeg;
                  const double step =
                      in[p] + o.step_weight * (ang / r) * (ang / r);
                  if (step < c) c = step, arg = p;
                }
              }
              if (o.jump_cost >= 0 && in_min + o.jump_cost < c) {
                c = in_min + o.jump_cost, arg = in_arg, jump = true;
              }
            }
            (*out_cost)[d] = c;
            if (back_row) back_row[d] = arg;
            if (jumped_row) jumped_row[d] = hard || jump;
          }
        });
  };

  // Forward: alpha[t][d], the best path's cost over frames 0..t ending at d.
  // Kept whole, with the back-pointers, when they fit in keep_forward_mb;
  // else memory stays flat in the clip's length: alpha is kept only every
  // kCheckpointFrames frames, and the backtrack and the backward pass run
  // block by block from the end, each block's alpha and back-pointers
  // computed again from its checkpoint (one more forward pass in all).
  const double whole_mb = static_cast<double>(T) * D *
                          (sizeof(float) + sizeof(int) + sizeof(uint8_t)) / 1e6;
  const bool keep_whole = whole_mb <= o.keep_forward_mb;
  const int block_frames = keep_whole ? T : kCheckpointFrames;
  const int blocks = (T + block_frames - 1) / block_frames;
  std::vector<double> checkpoint(static_cast<size_t>(blocks) * D);
  std::vector<double> cost(D), next(D);
  std::vector<float> alpha(static_cast<size_t>(block_frames) * D);
  std::vector<int> back(static_cast<size_t>(block_frames) * D, -1);
  std::vector<uint8_t> jumped(static_cast<size_t>(block_frames) * D, 0);
  // One forward step into frame t: `cost` becomes alpha[t]; the step's
  // back-pointers and alpha go to row `row` of the kept arrays, or nowhere
  // (row < 0).
  auto forward = [&](int t, int64_t row) {
    const size_t at = static_cast<size_t>(std::max<int64_t>(row, 0)) * D;
    relax(cost, t, &next, row >= 0 ? &back[at] : nullptr,
          row >= 0 ? &jumped[at] : nullptr);
    for (int d = 0; d < D; ++d) next[d] += o.evidence_weight * cost_of(t, d);
    std::swap(cost, next);
    if (row >= 0) std::copy(cost.begin(), cost.end(), alpha.begin() + at);
  };
  for (int d = 0; d < D; ++d) cost[d] = o.evidence_weight * cost_of(0, d);
  if (keep_whole) std::copy(cost.begin(), cost.end(), alpha.begin());
  for (int t = 0; t < T; ++t) {
    if (t > 0) forward(t, keep_whole ? t : -1);
    if (t % block_frames == 0) {
      std::copy(cost.begin(), cost.end(),
                checkpoint.begin() + static_cast<size_t>(t / block_frames) * D);
    }
  }
  int d_end = static_cast<int>(std::min_element(cost.begin(), cost.end()) -
                               cost.begin());
  out.cost = cost[d_end];
  // Backward: beta[d] at frame t, the best cost of frames t+1..T-1 from d;
  // alpha + beta is the best whole path through (t, d). The path's own
  // margin at t: how much more the best path through a far direction costs.
  // Margins need directions well away from the chosen one.
  const double exclusion =
      std::max(o.rival_exclusion_deg, 2.5 * grid.spacing_deg());
  const double cos_x = std::cos(exclusion * kDeg);
  std::vector<double> beta(D, 0.0), ahead(D), beta_next(D);
  int d = d_end;
  for (int b = blocks - 1; b >= 0; --b) {
    const int t0 = b * block_frames, t1 = std::min(T, t0 + block_frames);
    // The block's alpha and back-pointers again, from its checkpoint (kept
    // whole, the clip is one block and they are there already).
    if (!keep_whole) {
      for (int dd = 0; dd < D; ++dd)
        cost[dd] = checkpoint[static_cast<size_t>(b) * D + dd];
      std::copy(cost.begin(), cost.end(), alpha.begin());
      for (int t = t0 + 1; t < t1; ++t) forward(t, t - t0);
    }
    // Into the next block's first frame: its back-pointers come from this
    // block's last alpha (now in `cost`).
    if (t1 < T) {
      std::vector<int> back_row(D);
      std::vector<uint8_t> jumped_row(D);
      relax(cost, t1, &next, back_row.data(), jumped_row.data());
      out.jump_before[t1] = jumped_row[d];
      d = back_row[d];
    }
    for (int t = t1 - 1; t >= t0; --t) {
      if (t < T - 1) {
        for (int dd = 0; dd < D; ++dd)
          ahead[dd] = beta[dd] + o.evidence_weight * cost_of(t + 1, dd);
        relax(ahead, t + 1, &beta_next, nullptr, nullptr);
        std::swap(beta, beta_next);
      }
      out.direction[t] = d;
      const size_t row = static_cast<size_t>(t - t0) * D;
      if (t > t0) {
        out.jump_before[t] = jumped[row + d];
        d = back[row + d];
      }
      const int c = out.direction[t];
      const float* alpha_t = &alpha[row];
      double path_rival = kInf;
      for (int k = 0; k < D; ++k) {
        if (grid.direction(k).dot(grid.direction(c)) < cos_x) {
          path_rival = std::min(path_rival, alpha_t[k] + beta[k]);
        }
      }
      out.path_margin[t] = static_cast<float>(
          std::min(1e6, path_rival - (alpha_t[c] + beta[c])));
    }
  }
  // Per frame: the frame's own support for the chosen direction: how much
  // more the best direction well away from it costs (log-likelihood).
  for (int t = 0; t < T; ++t) {
    const int c = out.direction[t];
    const double own = evidence_cost(t, c);
    double rival = 1e9;
    for (int k = 0; k < D; ++k) {
      if (grid.direction(k).dot(grid.direction(c)) < cos_x)
        rival = std::min(rival, evidence_cost(t, k));
    }
    out.explained[t] = static_cast<float>(evidence.BestExplained(t));
    out.significance[t] = static_cast<float>(evidence.Significance(t));
    out.margin[t] = static_cast<float>(rival - own);
    out.measured[t] = used(t) && out.significance[t] >= o.min_significance &&
                      out.margin[t] >= o.min_margin;
  }
  out.status = SunPathResult::Status::kSuccess;
  return out;
}

}  // namespace sunlapse
