#include "sunlapse/common/robust_fit.h"

#include <algorithm>
#include <cmath>

namespace sunlapse {

namespace {

// Weighted normal equations of y = a + b x, solved with a, b >= 0.
void SolveGroup(double s0, double sx, double sxx, double sy, double sxy,
                double* a, double* b) {
  const double det = s0 * sxx - sx * sx;
  const bool solvable = s0 > 0 && det > 1e-9 * s0 * std::max(sxx, 1e-12);
  *a = *b = 0;
  if (solvable) {
    *a = (sxx * sy - sx * sxy) / det;
    *b = (s0 * sxy - sx * sy) / det;
  }
  if (!solvable || *b <= 0) {  // no contrast to explain: albedo x ambient only
    *b = 0;
    *a = s0 > 0 ? sy / s0 : 0;
  } else if (*a < 0) {
    *a = 0;
    *b = sxx > 0 ? sxy / sxx : 0;
  }
}

}  // namespace

void RobustAffineFit(int n, const float* x, const float* y, const int* group,
                     int num_groups, double scale, int iterations,
                     AffineFit* fit) {
  const double inv_c2 = 1.0 / (scale * scale);
  fit->a.assign(num_groups, 0.0);
  fit->b.assign(num_groups, 0.0);
  fit->residual.assign(n, 0.0);
  double* residual = fit->residual.data();
  // Weights are recomputed from the residuals: the first pass has none yet.
  auto weight = [&](int i, int iter) {
    return iter == 0 ? 1.0 : 1.0 / (1.0 + residual[i] * residual[i] * inv_c2);
  };
  for (int iter = 0; iter < iterations; ++iter) {
    if (!group) {  // one group: the common case, kept free of indirection
      double s0 = 0, sx = 0, sxx = 0, sy = 0, sxy = 0;
      for (int i = 0; i < n; ++i) {
        const double xi = x[i], yi = y[i], wi = weight(i, iter);
        s0 += wi;
        sx += wi * xi;
        sxx += wi * xi * xi;
        sy += wi * yi;
        sxy += wi * xi * yi;
      }
      SolveGroup(s0, sx, sxx, sy, sxy, &fit->a[0], &fit->b[0]);
      const double a = fit->a[0], b = fit->b[0];
      for (int i = 0; i < n; ++i) residual[i] = y[i] - (a + b * x[i]);
      continue;
    }
    std::vector<double> sums(5 * num_groups, 0.0);
    for (int i = 0; i < n; ++i) {
      const int g = group[i];
      if (g < 0) continue;
      const double xi = x[i], yi = y[i], wi = weight(i, iter);
      double* m = &sums[5 * g];
      m[0] += wi;
      m[1] += wi * xi;
      m[2] += wi * xi * xi;
      m[3] += wi * yi;
      m[4] += wi * xi * yi;
    }
    for (int g = 0; g < num_groups; ++g) {
      const double* m = &sums[5 * g];
      SolveGroup(m[0], m[1], m[2], m[3], m[4], &fit->a[g], &fit->b[g]);
    }
    for (int i = 0; i < n; ++i) {
      const int g = group[i];
      if (g >= 0) residual[i] = y[i] - (fit->a[g] + fit->b[g] * x[i]);
    }
  }
  // Sum of log(1 + r^2/c^2) as the log of products of up to 8 terms: one log
  // per 8 samples instead of one each (a product is flushed early before it
  // could leave double's range).
  double cost = 0, product = 1;
  int in_product = 0;
  for (int i = 0; i < n; ++i) {
    if (group && group[i] < 0) continue;
    product *= 1.0 + residual[i] * residual[i] * inv_c2;
    if (++in_product == 8 || product > 1e250) {
      cost += std::log(product);
      product = 1;
      in_product = 0;
    }
  }
  cost += std::log(product);
  fit->cost = cost;
}

}  // namespace sunlapse
