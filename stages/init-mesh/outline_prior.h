// The page's outline in 3D as the shape of blank paper.
//
// densify triangulates the real sides of the page (its outline points). The
// Coons patch of the four sides in 3D is the page exactly where it is folded
// along lines that run from side to side (each fold a straight line between
// two points of the outline: a ruled surface), and there the points inside
// the page, often only a few rows of print, cannot tell a panel's blank middle
// from a bulge (a receipt whose folds cross blank paper; see
// docs/decisions/init-mesh.md, "The outline prior"). Where the points
// disagree with the patch (a fold from a side to the next side, a curl, a
// flap), the points decide.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"

namespace docunfold::init_mesh {

struct OutlinePriorOptions {
  bool enabled = true;
  // An outline point belongs to a real side when its pixel lies within this
  // distance of the side's polyline (pixels).
  double side_distance_px = 3;
  // A side with fewer outline points is taken as straight between its
  // corners; with fewer than `min_measured_sides` measured sides (a page cut
  // off by the image border) there is no prior.
  int min_side_points = 10;
  int min_measured_sides = 3;
  // At each grid vertex the `neighbours` nearest points judge the prior: the
  // inverse depth the points add to the patch is their weighted mean
  // residual, weights 1/(1 + (r / radius)^2) with radius `radius_fraction` of
  // the image diagonal, against `prior_weight` for adding nothing (far from
  // every point the patch stands); and the patch counts with weight
  // exp(-(e / agreement)^2), e the weighted rms of their residuals relative to
  // depth, the points' own planar fit (DepthField) with the rest.
  int neighbours = 32;
  double radius_fraction = 0.01;
  double prior_weight = 0.5;
  double agreement = 0.005;
};

struct OutlinePriorResult {
  bool used = false;
  std::string note;                  // why not, when not used
  std::array<int, 4> side_points{};  // outline points per side (top right bottom left)
  int measured_sides = 0;
  std::vector<double> depth;  // per grid vertex: camera depth, when used
  double mean_weight = 0;     // of the patch, over the grid vertices
};

// `sides`: polylines of the four sides in pixels, `real`: which are real.
// `grid_pixels`/`grid_depths`: the image grid (row-major, `grid`) and the
// depth the points alone give its vertices. `outline_*`: the outline points'
// pixels and camera depths; `point_*`: every point used for depth.
OutlinePriorResult OutlinePriorDepths(
    const QuadGrid& grid, const std::vector<Eigen::Vector2d>& grid_pixels,
    const std::vector<double>& grid_depths,
    const std::array<std::vector<Eigen::Vector2d>, 4>& sides, const std::array<bool, 4>& real,
    const PinholeCamera& camera, const std::vector<Eigen::Vector2d>& outline_pixels,
    const std::vector<double>& outline_depths, const std::vector<Eigen::Vector2d>& point_pixels,
    const std::vector<double>& point_depths, const OutlinePriorOptions& options);

}  // namespace docunfold::init_mesh
