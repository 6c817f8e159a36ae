#include "common/axis_direction.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace docunfold {

std::optional<Eigen::Vector2d> CarryDirection(const std::vector<Eigen::Vector2d>& from,
                                              const std::vector<Eigen::Vector2d>& to,
                                              const Eigen::Vector2d& direction, int min_pairs) {
  const size_t n = std::min(from.size(), to.size());
  if (n < size_t(std::max(min_pairs, 3))) return std::nullopt;
  // to = A^T [x y 1] for the 3x2 matrix A, by the normal equations.
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, 3, 2> atb = Eigen::Matrix<double, 3, 2>::Zero();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d a(from[i].x(), from[i].y(), 1);
    ata += a * a.transpose();
    atb += a * to[i].transpose();
  }
  if (!(std::abs(ata.determinant()) > 1e-12)) return std::nullopt;
  const Eigen::Matrix<double, 3, 2> x = ata.ldlt().solve(atb);
  const Eigen::Vector2d carried = x.topRows<2>().transpose() * direction;
  if (!(carried.norm() > 0)) return std::nullopt;
  return carried.normalized();
}

double WrapToQuarterTurn(double a) {
  a = std::fmod(a, 90.0);
  if (a > 45) a -= 90;
  if (a <= -45) a += 90;
  return a;
}

AxisDirection DominantAxisDirection(const std::vector<DirectionVote>& votes, double agree_deg) {
  AxisDirection out;
  for (const DirectionVote& v : votes) {
    out.length += v.length;
    ++out.lines;
  }
  if (votes.empty() || out.length <= 0) return out;
  // Length per half degree, smoothed over +-1.5 degrees (circular, period 90).
  constexpr int kBins = 180;
  std::vector<double> hist(kBins, 0.0);
  for (const DirectionVote& v : votes) {
    const int bin = int(std::floor((WrapToQuarterTurn(v.angle_deg) + 45) * 2));
    for (int k = -6; k <= 6; ++k)
      hist[((bin + k) % kBins + kBins) % kBins] +=
          v.length * std::exp(-0.5 * (k / 3.0) * (k / 3.0));
  }
  const int peak = int(std::max_element(hist.begin(), hist.end()) - hist.begin());
  const double centre = WrapToQuarterTurn(peak / 2.0 - 45 + 0.25);
  double sum = 0, weight = 0;
  for (const DirectionVote& v : votes) {
    const double d = WrapToQuarterTurn(v.angle_deg - centre);
    if (std::abs(d) > agree_deg) continue;
    sum += v.length * d;
    weight += v.length;
  }
  out.angle_deg = WrapToQuarterTurn(centre + (weight > 0 ? sum / weight : 0));
  out.share = weight / out.length;
  return out;
}

}  // namespace docunfold
