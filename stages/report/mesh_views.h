// Pictures of the 3D mesh M for the report, drawn with the project's own
// rasterizer: textured from the reference photo, shaded, with the quad
// wireframe and the SfM points.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"

namespace docunfold::report {

struct MeshViewOptions {
  int width = 560, height = 420;  // picture size, pixels
  double yaw_deg = 0;             // turn about the model, relative to the reference view
  double pitch_deg = 0;
  int max_wire_lines = 16;  // grid lines drawn per direction at most
  int max_points = 800;     // SfM points drawn at most (evenly subsampled)
};

// M seen from a virtual camera turned about M's centre, relative to the
// reference camera (which looks along +z of the world frame). `texture` is
// the reference photo seen by `reference`; empty for plain shading.
cv::Mat RenderMeshView(const MeshPair& mesh, const PinholeCamera& reference, const cv::Mat& texture,
                       const std::vector<Eigen::Vector3d>& points, const MeshViewOptions& options);

}  // namespace docunfold::report
