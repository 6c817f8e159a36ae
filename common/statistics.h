// Order statistics of samples, and the sub-pixel place of a sampled peak,
// shared by the stages.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace docunfold {

// The value at rank round(q * (n - 1)) of the n samples (q in [0, 1]; the
// median is q = 0.5, the upper one for even n); 0 when there are none.
double Quantile(std::vector<double> values, double q);

// Quantile(values, 0.5): the value at rank n / 2.
double Median(std::vector<double> values);

// Sub-pixel position of the local maximum g[i] (a parabola through it and
// its neighbours, 0 <= i - 1 and i + 1 < g.size()), as an offset in samples
// from i; 0 where the three do not curve down.
double ParabolaPeak(const std::vector<double>& g, int i);

// The value at rank `k` (0-based, k < n) of the samples, for a caller that
// fixes its rank another way than Quantile (e.g. n * 95 / 100).
template <typename T>
T NthSmallest(std::vector<T> values, size_t k) {
  std::nth_element(values.begin(), values.begin() + long(k), values.end());
  return values[k];
}

}  // namespace docunfold
