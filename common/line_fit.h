// The total-least-squares line through 2D points (page sides in M', a
// side's image in a photo).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace docunfold {

struct LineFit2d {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();       // the points' mean
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();  // unit, along the line
  Eigen::Vector2d normal = Eigen::Vector2d::UnitY();     // unit, across it
  double rms = 0;                                        // RMS distance of the points to the line
};

// The line minimising the squared distances of `points` (at least one) to it.
LineFit2d FitLineTotalLeastSquares(const std::vector<Eigen::Vector2d>& points);

}  // namespace docunfold
