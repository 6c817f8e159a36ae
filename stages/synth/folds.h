// An exact isometry of a flat sheet: non-crossing fold lines, each a
// cylindrical bend of width w by an angle a (the strip of width w is bent
// into a circular arc, the panels either side stay flat). A narrow bend is a
// crease, a wide one a curl.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>
#include <vector>

namespace docunfold::synth {

struct Fold {
  Eigen::Vector2d point;      // a point of the fold's centre line (page metres)
  Eigen::Vector2d direction;  // unit direction of the line
  double width = 0.004;       // width of the bent strip, metres
  double angle = 0;           // bend angle in radians; > 0 bends towards +z
};

// The deformation. Page coordinates (u, v) in metres, u right, v down, the
// sheet [0, W] x [0, H]; the flat sheet lies in z = 0 before bending.
class FoldedSheet {
 public:
  FoldedSheet(double width_m, double height_m, std::vector<Fold> folds);

  // 3D position of page point (u, v) (before placing the sheet in a scene).
  Eigen::Vector3d Map(const Eigen::Vector2d& uv) const;
  const std::vector<Fold>& folds() const { return folds_; }
  double width() const { return width_; }
  double height() const { return height_; }

 private:
  // Signed distance of a page point from fold i's line, > 0 away from the
  // root panel (the panel holding the page centre).
  double Side(int i, const Eigen::Vector2d& uv) const;

  double width_, height_;
  std::vector<Fold> folds_;  // normals oriented away from the root
  std::vector<Eigen::Vector2d> normals_;
  std::vector<int> order_;                   // folds sorted from the root outwards
  std::vector<Eigen::Isometry3d> far_side_;  // rigid motion of the far side
};

struct FoldOptions {
  int creases = 1;  // number of narrow folds
  // Metres; a crease_width_max below crease_width_min counts as that.
  double crease_width_min = 0.003, crease_width_max = 0.008;
  double crease_angle_min = 30, crease_angle_max = 120;  // degrees
  bool curl = false;                                     // one extra wide bend
  double curl_width_min = 0.04, curl_width_max = 0.09;   // metres
  double curl_angle_min = 30, curl_angle_max = 70;       // degrees
  double max_total_angle = 125;  // |sum of signed angles| on any path, degrees
};

// Random non-crossing folds for a sheet; deterministic for the generator's
// state. Lines keep their strips apart and stay away from the corners. The
// result begins with `fixed` (folds the caller placed: a flap, a steep end,
// an end curl), which the random creases keep clear of. With fixed folds or
// creases over max_total_angle, a fold set is kept only if the folded sheet
// does not pass through itself (SelfIntersects); a crease over
// max_total_angle raises the limit on any path to its angle.
std::vector<Fold> RandomFolds(double width_m, double height_m, const FoldOptions& options,
                              std::mt19937* rng, const std::vector<Fold>& fixed = {});

// Whether the folded sheet, sampled as a triangle mesh at `spacing` metres,
// passes through itself: an edge of one triangle crossing another triangle
// that shares no vertex with it.
bool SelfIntersects(const FoldedSheet& sheet, double spacing);

// Printed-side conventions of FoldedSheet: the printed side of the flat sheet
// faces -z (d/dv x d/du), so a fold with a negative angle turns its far side
// towards the print: up off the table once the sheet is placed print up.
constexpr double kTowardsPrint = -1;

enum class Flap { kNone, kCorner, kEnd };
enum class PageEnd { kNone, kTop, kBottom, kBoth };

// Shapes that docunfold finds hard, placed on purpose rather than at random.
// Ends are the short sides' ends of the page: top (v = 0) and bottom (v = H).
struct ShapeOptions {
  Flap flap = Flap::kNone;  // a corner or an end folded back over the page
  double flap_angle = 176;  // degrees; 180 lies flat on the page
  double steep_angle = 0;   // degrees; > 0 adds a crease near an end bent up by it
  PageEnd end_curl = PageEnd::kNone;
  double end_curl_length = 0.035;  // metres of the page that curl
  double end_curl_angle = 150;     // degrees the end turns, in all
  bool any() const { return flap != Flap::kNone || steep_angle > 0 || end_curl != PageEnd::kNone; }
};

// The folds of `shapes` for a W x H sheet (random sizes and ends from the
// generator; nothing drawn when shapes.any() is false). Each bends towards
// the print. Crease widths come from `folds`. Throws std::invalid_argument
// when the shapes need more ends than the page has.
std::vector<Fold> ShapeFolds(double width_m, double height_m, const ShapeOptions& shapes,
                             const FoldOptions& folds, std::mt19937* rng);

}  // namespace docunfold::synth
