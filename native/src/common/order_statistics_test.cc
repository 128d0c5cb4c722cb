#include "sunlapse/common/order_statistics.h"

#include <gtest/gtest.h>

#include <vector>

namespace sunlapse {
namespace {

TEST(MedianInPlace, TakesTheUpperMiddleOfAnEvenCount) {
  std::vector<float> odd = {5, 1, 4, 2, 3};
  EXPECT_EQ(MedianInPlace(&odd), 3.f);
  std::vector<double> even = {4, 1, 3, 2};
  EXPECT_EQ(MedianInPlace(&even), 3.0);  // rank 2 of 0..3
  std::vector<int> one = {7};
  EXPECT_EQ(MedianInPlace(&one), 7);
}

TEST(MedianInPlace, WorksOnARawRange) {
  double values[] = {9, 8, 7, 6, 5, 4, 3};
  EXPECT_EQ(MedianInPlace(values, values + 7), 6.0);
}

TEST(QuantileInPlace, TakesRankFloorQTimesNClampedToTheLast) {
  std::vector<float> v(10);
  for (int i = 0; i < 10; ++i) v[i] = static_cast<float>(9 - i);
  EXPECT_EQ(QuantileInPlace(&v, 0.0), 0.f);
  EXPECT_EQ(QuantileInPlace(&v, 0.8), 8.f);   // rank 8
  EXPECT_EQ(QuantileInPlace(&v, 0.75), 7.f);  // rank floor(7.5)
  EXPECT_EQ(QuantileInPlace(&v, 1.0), 9.f);   // clamped to the last
}

}  // namespace
}  // namespace sunlapse
