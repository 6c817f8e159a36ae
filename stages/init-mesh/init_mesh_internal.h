// init-mesh's steps, shared by its source files (not part of its interface).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/grid_mesh.h"
#include "common/page_files.h"
#include "stages/init-mesh/init_mesh.h"

namespace docunfold::init_mesh {

// The world point on the page seen at a pixel of the reference image (the
// pixel lifted to the depth the points give it).
using Lift = std::function<Eigen::Vector3d(const Eigen::Vector2d&)>;

// The grid M^r in the reference image: its vertices' pixels, row-major.
struct ImageGrid {
  QuadGrid grid;
  std::vector<Eigen::Vector2d> pixels;
};

// --- image_grid.cc

// `n` points along the polyline `points`, equally spaced in `arc` (its
// cumulative length at each point, from 0; at least two points).
std::vector<Eigen::Vector2d> AtEqualArcLength(const std::vector<Eigen::Vector2d>& points,
                                              const std::vector<double>& arc, int n);

// Densifies a polyline to steps of at most `step` pixels.
std::vector<Eigen::Vector2d> Densify(const std::vector<Eigen::Vector2d>& p, double step);

// Coons patch of the four boundary sides, each resampled by arc length on
// the page (through `lift`); false (and why) when the boundary cannot
// support it: a side too short, not meeting its corners, a patch that folds
// over or lies mostly outside `region`.
bool CoonsGrid(const Boundary& b, const GridQuads& quads, const Lift& lift, const cv::Mat1b& region,
               ImageGrid* out, std::string* why);

// A grid over the bounding box of `mask`, its long side along the box's
// longer side on the page.
ImageGrid BoundingBoxGrid(const cv::Mat1b& mask, const GridQuads& quads, const Lift& lift);

// Where on the page (ninths of the grid) the points at `pixels` fall. Throws
// InputError when they cover less than `min_covered_ninths` of it; otherwise
// returns a warning naming each third (left, right, top, bottom) without
// points, empty when every third has some: the mesh is carried over such a
// part by fairness and isometry alone (a panel of a fold seen by one other
// photo has none).
std::string CheckCoverage(const ImageGrid& g, const std::vector<Eigen::Vector2d>& pixels, int width,
                          int height, const Options& o, const std::string& image);

// --- flat_mesh.cc

// Re-grids the pair uniformly on the page: a Coons patch of the border of
// M' (each border polyline resampled by arc length in the plane), mapped
// back onto M through the pair's own correspondence. Returns `m` unchanged
// when M' is not a simple region.
MeshPair RegridOnPage(const MeshPair& m);

// Turns M' (res->meshes) upright by the oriented bounding box of the real
// boundary sides (of the whole mesh when fewer than 10 of their points are
// found on it), then moves it to start at (0, 0); records the rotation and
// what it was taken from in `res`.
void TurnUpright(const Inputs& in, Result* res);

}  // namespace docunfold::init_mesh
