#include "common/line_fit.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace docunfold {

LineFit2d FitLineTotalLeastSquares(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p;
  mean /= double(points.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const auto& p : points) scatter += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(scatter);
  LineFit2d fit;
  fit.point = mean;
  fit.direction = eigen.eigenvectors().col(1).normalized();  // the larger eigenvalue
  fit.normal = eigen.eigenvectors().col(0);
  fit.rms = std::sqrt(std::max(0.0, eigen.eigenvalues()(0)) / double(points.size()));
  return fit;
}

}  // namespace docunfold
