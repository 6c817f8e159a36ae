// Straight lines through baseline samples: a least-squares fit, and the
// cuts where a baseline bends.
#include <algorithm>
#include <cmath>

#include "stages/detect-features/feature_parts.h"

namespace docunfold::features::detail {

LineFit FitLine(const std::vector<cv::Point2d>& points) {
  LineFit fit;
  if (points.empty()) return fit;
  cv::Point2d mean(0, 0);
  for (const auto& p : points) mean += p;
  mean *= 1.0 / double(points.size());
  double sxx = 0, sxy = 0, syy = 0;
  for (const auto& p : points) {
    const cv::Point2d d = p - mean;
    sxx += d.x * d.x;
    sxy += d.x * d.y;
    syy += d.y * d.y;
  }
  const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy);
  fit.direction = {std::cos(angle), std::sin(angle)};
  fit.point = mean;
  double r2 = 0;
  for (const auto& p : points) {
    const cv::Point2d d = p - mean;
    const double r = d.x * -fit.direction.y + d.y * fit.direction.x;
    r2 += r * r;
  }
  fit.rms = std::sqrt(r2 / double(points.size()));
  return fit;
}

std::vector<std::pair<int, int>> SplitWhereBent(const std::vector<cv::Point2d>& points,
                                                double tolerance) {
  std::vector<std::pair<int, int>> out;
  if (points.size() < 2) {
    if (!points.empty()) out.emplace_back(0, 0);
    return out;
  }
  std::vector<std::pair<int, int>> stack = {{0, int(points.size()) - 1}};
  while (!stack.empty()) {
    auto [a, b] = stack.back();
    stack.pop_back();
    const cv::Point2d chord = points[b] - points[a];
    const double len = cv::norm(chord);
    int worst = -1;
    double worst_d = tolerance;
    for (int k = a + 1; k < b; ++k) {
      const cv::Point2d v = points[k] - points[a];
      const double d = len > 1e-9 ? std::abs(chord.x * v.y - chord.y * v.x) / len : cv::norm(v);
      if (d > worst_d) {
        worst_d = d;
        worst = k;
      }
    }
    if (worst < 0) {
      out.emplace_back(a, b);
    } else {
      stack.emplace_back(worst, b);
      stack.emplace_back(a, worst);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace docunfold::features::detail
