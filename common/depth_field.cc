#include "common/depth_field.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace docunfold {

DepthField::DepthField(std::vector<Eigen::Vector2d> pixels, std::vector<double> depths, int k,
                       double scale, DepthModel model, int planar_k)
    : pixels_(std::move(pixels)),
      depths_(std::move(depths)),
      k_(k),
      scale_(scale),
      model_(model),
      planar_k_(planar_k),
      index_(std::make_unique<PointIndex2d>(pixels_)) {}

DepthField::~DepthField() = default;

double DepthField::At(const Eigen::Vector2d& px) const {
  const bool planar = model_ == DepthModel::kPlanar;
  const std::vector<std::pair<int, double>> nearest =
      index_->Nearest(px, planar ? std::max(k_, planar_k_) : k_);
  double sw = 0, sz = 0;
  for (size_t i = 0; i < std::min<size_t>(nearest.size(), size_t(k_)); ++i) {
    const double weight = 1 / (1 + nearest[i].second / (scale_ * scale_));
    sw += weight;
    sz += weight * depths_[nearest[i].first];
  }
  const double average = sz / sw;
  if (!planar) return average;
  const double inv =
      PlanarInverseDepth(px, nearest, std::min<size_t>(nearest.size(), size_t(planar_k_)));
  return std::isfinite(inv) ? 1 / inv : average;
}

double DepthField::PlanarInverseDepth(const Eigen::Vector2d& px,
                                      const std::vector<std::pair<int, double>>& nearest,
                                      size_t n) const {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (n < 6) return kNaN;
  // 1/z = c + a·du + b·dv around px (weighted normal equations). The
  // weights' unit is at least the farthest neighbour's distance: with the
  // points' spacing as unit (often ~1 px where text is dense) the nearest
  // two or three would decide the slope alone and extrapolate it wildly.
  const double unit2 = std::max(scale_ * scale_, nearest[n - 1].second);
  const double unit = std::sqrt(unit2);
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double lo = 1e300, hi = 0;
  for (size_t i = 0; i < n; ++i) {
    const auto& [index, d2] = nearest[i];
    const double weight = 1 / (1 + d2 / unit2);
    const Eigen::Vector2d d = (pixels_[index] - px) / unit;
    const Eigen::Vector3d row(1, d.x(), d.y());
    const double inv = 1 / depths_[index];
    A += weight * row * row.transpose();
    rhs += weight * inv * row;
    lo = std::min(lo, inv);
    hi = std::max(hi, inv);
  }
  // Points (nearly) on a line (one text line) leave the slope across it
  // free: then the average. Their weighted covariance about their mean:
  const Eigen::Vector2d mean = A.block<2, 1>(1, 0) / A(0, 0);
  const Eigen::Matrix2d covariance =
      A.bottomRightCorner<2, 2>() / A(0, 0) - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> spread(covariance);
  if (!(spread.eigenvalues()(0) >= 1e-2 * spread.eigenvalues()(1))) return kNaN;
  const double inv = A.ldlt().solve(rhs)(0);
  // Far from every point a slope would run away: stay within the
  // neighbours' range (measured on set08, whose page leaves the picture:
  // widening it by half on each side put M 14 % of the diagonal off the
  // true surface where the border cuts the page, 5 % without).
  if (!(inv > 0)) return kNaN;
  return std::clamp(inv, lo, hi);
}

}  // namespace docunfold
