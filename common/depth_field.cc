#include "common/depth_field.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cstdint>
#include <tuple>

namespace docunfold {

DepthField::DepthField(std::vector<Eigen::Vector2d> pixels,
                       std::vector<double> depths, int k, double scale,
                       DepthModel model, int planar_k)
    : pixels_(std::move(pixels)),
      depths_(std::move(depths)),
      k_(k),
      scale_(scale),
      model_(model),
      planar_k_(planar_k),
      index_(std::make_unique<PointIndex2d>(pixels_)) {}

DepthField::~DepthField() = default;

double DepthField::At(const Eigen::Vector2d& px) const {
  const int want = model_ == DepthModel::kPlanar ? std::max(k_, planar_k_) : k_;
  const std::vector<std::pair<int, double>> nearest = index_->Nearest(px, want);
  const size_t found = nearest.size();
  std::vector<int> idx(found);
  std::vector<double> d2(found);
  for (size_t i = 0; i < found; ++i) std::tie(idx[i], d2[i]) = nearest[i];
  auto weight = [&](size_t i) { return 1 / (1 + d2[i] / (scale_ * scale_)); };
  double sw = 0, sz = 0;
  for (size_t i = 0; i < std::min<size_t>(found, size_t(k_)); ++i) {
    sw += weight(i);
    sz += weight(i) * depths_[idx[i]];
  }
  const double average = sz / sw;
  if (model_ != DepthModel::kPlanar || found < 6) return average;
  // 1/z = c + a·du + b·dv around px (weighted normal equations). The
  // weights' unit is at least the farthest neighbour's distance: with the
  // points' spacing as unit (often ~1 px where text is dense) the nearest
  // two or three would decide the slope alone and extrapolate it wildly.
  const double unit2 = std::max(scale_ * scale_, d2[found - 1]);
  auto planar_weight = [&](size_t i) { return 1 / (1 + d2[i] / unit2); };
  const double unit = std::sqrt(unit2);
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double lo = 1e300, hi = 0;
  for (size_t i = 0; i < found; ++i) {
    const Eigen::Vector2d d = (pixels_[idx[i]] - px) / unit;
    const Eigen::Vector3d row(1, d.x(), d.y());
    const double inv = 1 / depths_[idx[i]];
    A += planar_weight(i) * row * row.transpose();
    rhs += planar_weight(i) * inv * row;
    lo = std::min(lo, inv);
    hi = std::max(hi, inv);
  }
  // Points (nearly) on a line (one text line) leave the slope across it
  // free: then the average. Their weighted covariance about their mean:
  const Eigen::Vector2d mean = A.block<2, 1>(1, 0) / A(0, 0);
  const Eigen::Matrix2d covariance =
      A.bottomRightCorner<2, 2>() / A(0, 0) - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> spread(covariance);
  if (!(spread.eigenvalues()(0) >= 1e-2 * spread.eigenvalues()(1)))
    return average;
  const double inv = A.ldlt().solve(rhs)(0);
  // Far from every point a slope would run away: stay within the
  // neighbours' range (measured on set08, whose page leaves the picture:
  // widening it by half on each side put M 14 % of the diagonal off the
  // true surface where the border cuts the page, 5 % without).
  if (!(inv > 0)) return average;
  return 1 / std::clamp(inv, lo, hi);
}

}  // namespace docunfold
