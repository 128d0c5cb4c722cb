#include "sunlapse/common/robust_fit.h"

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>

namespace sunlapse {

void RobustAffineFit(int n, const float* x, const float* y, const int* group,
                     int num_groups, double scale, int iterations,
                     AffineFit* fit) {
  const double c2 = scale * scale;
  fit->a.assign(num_groups, 0.0);
  fit->b.assign(num_groups, 0.0);
  fit->residual.assign(n, 0.0);
  std::vector<double> w(n, 1.0);
  auto g_of = [&](int i) { return group ? group[i] : 0; };
  for (int iter = 0; iter < iterations; ++iter) {
    std::vector<Eigen::Matrix2d> ata(num_groups, Eigen::Matrix2d::Zero());
    std::vector<Eigen::Vector2d> atb(num_groups, Eigen::Vector2d::Zero());
    for (int i = 0; i < n; ++i) {
      const int g = g_of(i);
      if (g < 0) continue;
      const double xi = x[i], yi = y[i], wi = w[i];
      Eigen::Matrix2d& m = ata[g];
      m(0, 0) += wi;
      m(0, 1) += wi * xi;
      m(1, 1) += wi * xi * xi;
      atb[g] += wi * Eigen::Vector2d(yi, xi * yi);
    }
    for (int g = 0; g < num_groups; ++g) {
      Eigen::Matrix2d& m = ata[g];
      m(1, 0) = m(0, 1);
      double a = 0, b = 0;
      const double det = m.determinant();
      const bool solvable = m(0, 0) > 0 && det > 1e-9 * m(0, 0) * std::max(m(1, 1), 1e-12);
      if (solvable) {
        const Eigen::Vector2d ab = m.inverse() * atb[g];
        a = ab[0];
        b = ab[1];
      }
      if (!solvable || b <= 0) {  // no contrast to explain: albedo x ambient only
        b = 0;
        a = m(0, 0) > 0 ? atb[g][0] / m(0, 0) : 0;
      } else if (a < 0) {
        a = 0;
        b = m(1, 1) > 0 ? atb[g][1] / m(1, 1) : 0;
      }
      fit->a[g] = a;
      fit->b[g] = b;
    }
    for (int i = 0; i < n; ++i) {
      const int g = g_of(i);
      if (g < 0) continue;
      const double r = y[i] - (fit->a[g] + fit->b[g] * x[i]);
      fit->residual[i] = r;
      w[i] = 1.0 / (1.0 + r * r / c2);
    }
  }
  fit->cost = 0;
  for (int i = 0; i < n; ++i) {
    if (g_of(i) >= 0) fit->cost += std::log1p(fit->residual[i] * fit->residual[i] / c2);
  }
}

}  // namespace sunlapse
