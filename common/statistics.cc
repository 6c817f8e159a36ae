#include "common/statistics.h"

#include <algorithm>

namespace docunfold {

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1, size_t(q * (values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + long(k), values.end());
  return values[k];
}

double Median(std::vector<double> values) { return Quantile(std::move(values), 0.5); }

double ParabolaPeak(const std::vector<double>& g, int i) {
  const double curvature = g[i - 1] - 2 * g[i] + g[i + 1];
  return curvature < 0 ? 0.5 * (g[i - 1] - g[i + 1]) / curvature : 0;
}

}  // namespace docunfold
