// A small triangle rasterizer with a depth buffer. It returns, for every
// pixel centre, the nearest triangle and perspective-correct barycentric
// coordinates, from which any per-vertex attribute can be interpolated
// (texture coordinates for synth and render, face ids for markers, ...).
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "common/camera.h"

namespace docunfold {

struct RasterResult {
  cv::Mat1f depth;  // camera depth of the nearest surface; +inf where empty
  cv::Mat1i face;   // index of the nearest triangle; -1 where empty
  cv::Mat2f bary;   // perspective-correct (b1, b2) of that triangle; b0 = 1-b1-b2
};

using Triangle = std::array<int, 3>;

// Rasterizes triangles whose vertices are given in screen space as (pixel x,
// pixel y, camera depth z). Pixel centres are at integer coordinates.
// Triangles with a vertex at depth <= `near_depth` are skipped.
RasterResult Rasterize(const std::vector<Eigen::Vector3d>& screen_vertices,
                       const std::vector<Triangle>& triangles, int width, int height,
                       double near_depth = 1e-6);

namespace internal {
struct ScreenTriangle;  // one triangle as Rasterize draws it (raster.cc)
}

// Which triangle Rasterize would leave at a pixel centre, one pixel at a
// time: for a few thousand pixels of a large image (markers cast every
// iteration) it saves filling, and clearing, three full-size buffers. Same
// coverage test, depth test and order as Rasterize, so the same answer.
class PixelFaceIndex {
 public:
  PixelFaceIndex(const std::vector<Eigen::Vector3d>& screen_vertices,
                 const std::vector<Triangle>& triangles, int width, int height,
                 double near_depth = 1e-6);
  ~PixelFaceIndex();
  PixelFaceIndex(const PixelFaceIndex&);
  PixelFaceIndex(PixelFaceIndex&&) noexcept;
  // Rasterize(...).face(y, x): the triangle's index, -1 where empty or off
  // the image.
  int operator()(int x, int y) const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  static constexpr int kCell = 8;  // pixels per side of a bucket
  int width_, height_, cells_x_, cells_y_;
  std::vector<internal::ScreenTriangle> screen_;  // the triangles Rasterize draws
  std::vector<int> face_;                         // their indices in `triangles`
  std::vector<int> cell_start_;      // cell c lists cell_triangles_[start[c], start[c+1])
  std::vector<int> cell_triangles_;  // indices into screen_, ascending per cell
};

// Vertices in screen space for Rasterize: (pixel x, pixel y, camera depth)
// in `camera` scaled by `scale`, pixel centres at integer coordinates.
std::vector<Eigen::Vector3d> ScreenVertices(const PinholeCamera& camera,
                                            const std::vector<Eigen::Vector3d>& vertices,
                                            double scale = 1.0);

// Projects world-space vertices through `camera` and rasterizes them at
// the camera's image size scaled by `scale` (e.g. 2 for supersampling).
RasterResult RasterizeMesh(const PinholeCamera& camera,
                           const std::vector<Eigen::Vector3d>& vertices,
                           const std::vector<Triangle>& triangles, double scale = 1.0);

// PixelFaceIndex of RasterizeMesh's raster.
PixelFaceIndex MeshFaceIndex(const PinholeCamera& camera,
                             const std::vector<Eigen::Vector3d>& vertices,
                             const std::vector<Triangle>& triangles, double scale = 1.0);

// Interpolates per-vertex attributes (one row per vertex, one column per
// channel) over the raster; returns CV_32FC(channels), NaN where empty.
cv::Mat InterpolateAttributes(const RasterResult& raster, const std::vector<Triangle>& triangles,
                              const Eigen::MatrixXf& attributes);

// Splits polygons (quads from PLY files) into triangles by fanning.
std::vector<Triangle> Triangulate(const std::vector<std::vector<int>>& faces);

}  // namespace docunfold
