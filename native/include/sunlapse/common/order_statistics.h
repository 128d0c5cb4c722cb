// Order statistics of a sample, in place (std::nth_element: linear time, the
// values reordered). One definition for every stage: the reference levels,
// the noise scales and the medians of frames and residuals all take the
// element at floor(q * n), the upper median for q = 0.5.
#pragma once

#include <algorithm>
#include <cstddef>
#include <iterator>
#include <vector>

namespace sunlapse {

// The element of rank floor(q * n) (clamped to the last) of [first, last),
// which must not be empty; q in [0, 1]. The range is reordered.
template <class It>
typename std::iterator_traits<It>::value_type QuantileInPlace(It first, It last,
                                                              double q) {
  const auto n = static_cast<size_t>(std::distance(first, last));
  const size_t k =
      std::min(n - 1, static_cast<size_t>(q * static_cast<double>(n)));
  std::nth_element(first, first + static_cast<std::ptrdiff_t>(k), last);
  return first[static_cast<std::ptrdiff_t>(k)];
}

// The upper median (rank n / 2) of [first, last), which must not be empty.
template <class It>
typename std::iterator_traits<It>::value_type MedianInPlace(It first, It last) {
  const auto n = std::distance(first, last);
  std::nth_element(first, first + n / 2, last);
  return first[n / 2];
}

template <class T>
T MedianInPlace(std::vector<T>* v) {
  return MedianInPlace(v->begin(), v->end());
}

template <class T>
T QuantileInPlace(std::vector<T>* v, double q) {
  return QuantileInPlace(v->begin(), v->end(), q);
}

}  // namespace sunlapse
