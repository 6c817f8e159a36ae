// Order statistics of samples, shared by the stages.
#pragma once

#include <vector>

namespace docunfold {

// The value at rank round(q * (n - 1)) of the n samples (q in [0, 1]; the
// median is q = 0.5, the upper one for even n); 0 when there are none.
double Quantile(std::vector<double> values, double q);

// Quantile(values, 0.5).
double Median(std::vector<double> values);

}  // namespace docunfold
