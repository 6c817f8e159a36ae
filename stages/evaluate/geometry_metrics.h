// Geometry against the true surface (synthetic data sets): distance of the
// recovered 3D mesh M to the true page after a similarity alignment computed
// through the cameras, and the isometry error between M and its flat twin M'.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/ply.h"
#include "common/point_index.h"

namespace docunfold::evaluate {

// x_b = scale * R * x_a + t.
struct Similarity {
  double scale = 1;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d operator()(const Eigen::Vector3d& x) const { return scale * (R * x) + t; }
};

struct CameraAlignment {
  Similarity truth_from_sfm;
  int cameras = 0;          // views present in both sets
  double rms_residual = 0;  // of the camera centres, in truth units
};

// Similarity (Eigen::umeyama) taking the camera centres of `sfm` onto those of
// `truth`, matched by image name. Needs three views in both whose centres are
// not collinear; otherwise returns nullopt and says why in `why_not`.
std::optional<CameraAlignment> AlignCameras(const CameraSet& sfm, const CameraSet& truth,
                                            std::string* why_not);

// Unsigned distance from points to a triangle mesh. Candidate triangles are
// those around the nearest mesh vertices, exact for meshes whose triangles
// are small against the distances of interest (ground-truth meshes are
// dense); for a far-away point it is an upper bound close to the truth.
class SurfaceDistance {
 public:
  SurfaceDistance(std::vector<Eigen::Vector3d> vertices, std::vector<std::array<int, 3>> triangles);
  double operator()(const Eigen::Vector3d& point) const;

 private:
  PointIndex3d vertices_;  // the mesh's vertices (leaf size 16)
  std::vector<std::array<int, 3>> triangles_;
  std::vector<std::vector<int>> triangles_of_vertex_;
};

// Distance from a point to a triangle (Ericson, Real-Time Collision Detection).
double PointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c);

struct DistanceStats {
  double mean = 0;
  double max = 0;
  size_t samples = 0;
};
// Distances from every vertex of `mesh` (after `transform`) to `surface`.
DistanceStats MeshToSurface(const std::vector<Eigen::Vector3d>& vertices,
                            const Similarity& transform, const SurfaceDistance& surface);

struct IsometryStats {
  double mean = 0;  // mean of |len3 - len2| / len2 over the unique edges
  double max = 0;
  size_t edges = 0;
};
// Relative edge-length error between M and M' (same connectivity, same
// length unit). Throws InputError when the meshes do not correspond.
IsometryStats IsometryError(const PlyData& mesh3d, const PlyData& mesh2d,
                            const std::string& names_for_errors);

}  // namespace docunfold::evaluate
