// Unfolding M to the plane for the first M' (paper step 3 of
// "Initialization"; the paper uses BFF, any good parameterisation works as
// the joint optimisation refines it): as-rigid-as-possible parameterisation
// (Liu et al. 2008, local/global iterations with cotangent weights) of the
// triangulated grid. Rotations keep the orientation of the initial layout,
// so M' is never a mirror image of it.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "common/grid_mesh.h"

namespace docunfold::isometry {

struct UnfoldOptions {
  int max_iterations = 200;  // local/global iterations
  // Stop when the largest vertex move of an iteration is below this
  // fraction of the mean edge length.
  double tolerance = 1e-6;
};

struct UnfoldResult {
  std::vector<Eigen::Vector2d> mesh2d;  // in M's length unit
  int iterations = 0;
};

// `initial` is any non-folded layout of the grid in the plane (e.g. the grid
// vertices in the reference image); it is first scaled so that its total
// edge length matches M's.
UnfoldResult UnfoldArap(const QuadGrid& grid, const std::vector<Eigen::Vector3d>& mesh3d,
                        const std::vector<Eigen::Vector2d>& initial,
                        const UnfoldOptions& options = {});

}  // namespace docunfold::isometry
