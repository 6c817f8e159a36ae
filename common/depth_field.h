// Depth of a pixel of one camera from the depths of nearby projected points
// (init-mesh's grid, densify's prewarp of the other photos).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "common/point_index.h"

namespace docunfold {

enum class DepthModel { kAverage, kPlanar };

// Depth of a pixel from its nearest projected points, RBF weights
// φ(r) = 1/(1+r²), r = pixel distance / `scale`. kAverage: the weighted mean
// depth of the k nearest (the paper). kPlanar: a weighted least-squares fit
// of 1/depth as an affine function of the pixel over the `planar_k` nearest
// (r in units of the farthest of them), which is exact for a plane and so
// carries each panel on over blank paper (margins, gaps between columns)
// instead of levelling it to the nearest points' depth; it stays within
// those neighbours' depth range.
class DepthField {
 public:
  // `pixels` and `depths` (> 0) correspond; at least one point.
  DepthField(std::vector<Eigen::Vector2d> pixels, std::vector<double> depths, int k, double scale,
             DepthModel model, int planar_k);
  ~DepthField();
  DepthField(const DepthField&) = delete;
  DepthField& operator=(const DepthField&) = delete;

  double At(const Eigen::Vector2d& pixel) const;

 private:
  // 1/depth at `px` of the planar fit to the first `n` of `nearest` (pairs of
  // point index and squared pixel distance, nearest first); NaN where the
  // points leave the slope free (nearly collinear) or the fit is not positive.
  double PlanarInverseDepth(const Eigen::Vector2d& px,
                            const std::vector<std::pair<int, double>>& nearest, size_t n) const;

  std::vector<Eigen::Vector2d> pixels_;
  std::vector<double> depths_;
  int k_;
  double scale_;
  DepthModel model_;
  int planar_k_;
  std::unique_ptr<PointIndex2d> index_;
};

}  // namespace docunfold
