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
// state. Lines keep their strips apart and stay away from the corners.
std::vector<Fold> RandomFolds(double width_m, double height_m, const FoldOptions& options,
                              std::mt19937* rng);

}  // namespace docunfold::synth
