// Robust fit shared by the estimators: y = a + b x per group, a, b >= 0, by
// iteratively reweighted least squares with Cauchy weights. In the Lambertian
// model x is the shading (max(0, N.L) x visibility), a the ambient light and b
// the sun, each times the group's albedo.
#pragma once

#include <vector>

namespace sunlapse {

struct AffineFit {
  std::vector<double> a, b;      // per group
  std::vector<double> residual;  // per sample: y - (a + b x)
  double cost = 0.0;             // sum of log(1 + r^2 / scale^2)
};

// group may be null (one group). Samples with a group < 0 are ignored.
void RobustAffineFit(int n, const float* x, const float* y, const int* group,
                     int num_groups, double scale, int iterations,
                     AffineFit* fit);

}  // namespace sunlapse
