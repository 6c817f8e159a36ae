// The crop of the rectified page: boundary sides mapped onto M', straight
// lines fitted to them, the small rotation that makes them axis aligned,
// and the rectangle they bound (the paper's "Image generation of rectified
// document").
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"
#include "stages/render/render.h"

namespace docunfold::render {

// Samples a polyline of reference pixels about every pixel (at most
// `max_samples` points) and maps each sample onto M' through M. A sample
// whose viewing ray misses M is moved to the nearest pixel of M's raster
// within `snap_px` and intersected with that triangle's plane (the mesh
// border may run a pixel or two inside the segmented boundary); farther
// samples are dropped. `samples` receives the number of samples taken.
std::vector<Eigen::Vector2d> MapPolylineOntoFlat(const MeshPair& mesh, const PinholeCamera& camera,
                                                 const PixelToSurface& lookup,
                                                 const std::vector<Eigen::Vector2d>& polyline,
                                                 double snap_px, int* samples,
                                                 int max_samples = 4000);

// Fits a straight line to the points of side `side` (0 top, 1 right,
// 2 bottom, 3 left) by total least squares with MAD-based outlier removal.
// Directions point +x for top/bottom and +y for left/right. The side is
// `used` when at least 10 points and 30% of the samples survive.
SideFit FitSideLine(int side, bool real, const std::vector<Eigen::Vector2d>& flat_points,
                    int samples);

// Where a fitted side's line crosses x (top, bottom) or y (left, right).
double YAt(const SideFit& side, double x);
double XAt(const SideFit& side, double y);

// Angle (radians) by which the used sides say M' is turned away from
// upright: the weighted mean of each line's deviation from its axis. 0 when
// no side is used.
double TiltOfSides(const std::array<SideFit, 4>& sides);

// Rotates a fitted line (point and direction) by `angle` about the origin.
void RotateSide(SideFit* side, double angle);

struct CropRect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  std::string rule;  // boundary-lines | real-sides-and-visible-mesh | visible-mesh
  double Width() const { return x1 - x0; }
  double Height() const { return y1 - y0; }
};

// The axis-aligned rectangle inscribed in the lines of the used sides; on
// the sides that are not used, the box of the part of M' seen in the
// reference image (`visible_box`: x0 y0 x1 y1). Sides whose lines are in
// the wrong order (top below bottom, left right of right) are dropped
// (their `used` cleared, `note` set); a degenerate result falls back to the
// visible box.
CropRect ChooseCrop(std::array<SideFit, 4>* sides, const Eigen::Vector4d& visible_box);

// M' warped so that the used sides' lines become the crop's edges: where a
// line runs off its axis (M' a little wrong near that edge), the page between
// it and the opposite side is stretched or squeezed along that axis instead
// of the crop being inscribed at the line's tighter end. Separable: x' moves
// between the left and right lines at the point's y, y' between the top and
// bottom lines at its x; a side not used keeps the crop's edge.
struct SideWarp {
  std::array<bool, 4> active{};
  std::array<SideFit, 4> lines;
  CropRect crop;         // the crop after the warp: each active line where it
                         // crosses the middle of the other axis' extent
  double max_shift = 0;  // largest move of a crop corner, M' units
  Eigen::Vector2d Apply(const Eigen::Vector2d& p) const;
};

// The warp for the used sides within `max_slant` (radians) of their axes;
// none active (the identity) when no side qualifies.
SideWarp WarpToSides(const std::array<SideFit, 4>& sides, const CropRect& crop, double max_slant);

// A page cut off where no photo sees its edge ends somewhere past the crop;
// a paper format of long-to-short ratio `aspect` says where. Lengthens `crop`
// across the sides flagged in `unseen` (0 top, 1 right, 2 bottom, 3 left) to
// the shorter of W * aspect and W / aspect that is at least the part seen,
// W being the crop's extent across them; two unseen sides of one axis share
// the lengthening. Not applied when both axes have an unseen side (W is then
// not the page's) or the part seen is longer than W * aspect (+1 %: not that
// format).
PageFormatFit ExtendToPageFormat(CropRect* crop, const std::array<bool, 4>& unseen, double aspect);

// Angle (radians) of a side's line from its axis: from +x for top and
// bottom, from +y for left and right, positive clockwise in image axes.
double SlantOf(const SideFit& side, int index);

}  // namespace docunfold::render
