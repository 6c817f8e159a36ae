// Binary glTF (.glb) export of a textured triangle mesh via tinygltf, for
// glTF viewers and the browser report.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/raster.h"

namespace docunfold {

struct GltfMesh {
  std::string name = "mesh";
  std::vector<Eigen::Vector3d> positions;  // OpenCV axes; converted on export
  std::vector<Eigen::Vector2d> texcoords;  // (u, v), (0,0) = top left of texture
  std::vector<Triangle> triangles;
  cv::Mat texture;  // 8-bit BGR image, embedded as PNG; may be empty
};

// A coloured point cloud (drawn as glTF POINTS).
struct GltfPoints {
  std::string name = "points";
  std::vector<Eigen::Vector3d> positions;  // OpenCV axes; converted on export
  std::vector<Eigen::Vector3f> colors;     // linear RGB in [0, 1]; may be empty
};

// Writes one .glb with all meshes and point clouds as nodes of one scene
// (atomic; throws OutputError). Positions are turned from OpenCV axes (y
// down, z forward) into glTF's (y up, z backward) by flipping y and z.
void WriteGlb(const std::filesystem::path& path, const std::vector<GltfMesh>& meshes,
              const std::vector<GltfPoints>& points = {});

}  // namespace docunfold
