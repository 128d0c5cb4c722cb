#include "sunlapse/common/robust_fit.h"

#include <gtest/gtest.h>

namespace sunlapse {
namespace {

TEST(RobustAffineFit, RecoversLinesPerGroupDespiteOutliers) {
  std::vector<float> x, y;
  std::vector<int> g;
  for (int i = 0; i < 200; ++i) {
    const float xi = (i % 10) / 10.f;
    x.push_back(xi);
    g.push_back(i % 2);
    float yi = (i % 2 ? 0.3f + 0.5f * xi : 0.1f + 0.2f * xi);
    if (i % 17 == 0) yi += 0.8f;  // outliers
    y.push_back(yi);
  }
  AffineFit fit;
  RobustAffineFit(200, x.data(), y.data(), g.data(), 2, 0.02, 6, &fit);
  EXPECT_NEAR(fit.a[0], 0.1, 0.01);
  EXPECT_NEAR(fit.b[0], 0.2, 0.02);
  EXPECT_NEAR(fit.a[1], 0.3, 0.01);
  EXPECT_NEAR(fit.b[1], 0.5, 0.02);
}

TEST(RobustAffineFit, KeepsBothTermsNonNegative) {
  const float x[] = {0, 0.5f, 1, 0, 0.5f, 1};
  const float y[] = {0.9f, 0.5f, 0.1f,
                     0.9f, 0.5f, 0.1f};  // falling: b would be < 0
  AffineFit fit;
  RobustAffineFit(6, x, y, nullptr, 1, 0.1, 3, &fit);
  EXPECT_EQ(fit.b[0], 0.0);
  EXPECT_NEAR(fit.a[0], 0.5, 1e-6);
  const float y2[] = {-0.1f, 0.2f, 0.5f, -0.1f, 0.2f, 0.5f};  // a would be < 0
  RobustAffineFit(6, x, y2, nullptr, 1, 0.1, 3, &fit);
  EXPECT_EQ(fit.a[0], 0.0);
  EXPECT_GT(fit.b[0], 0.0);
}

}  // namespace
}  // namespace sunlapse
