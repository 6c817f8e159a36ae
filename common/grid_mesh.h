// The pair of meshes every later stage exchanges: M (mesh3d.ply, the page in
// the world frame) and M' (mesh2d.ply, its flat twin in z = 0), quad grids
// with the same connectivity, and the map from reference-image pixels onto
// them.
//
// File contract (40_init/, 50_optimize/, 50_optimize/roundK/):
//  - vertices row-major, `comment grid NX NY` (NX vertices per row, NY rows);
//  - quad faces (r,c) (r,c+1) (r+1,c+1) (r+1,c), row-major; quad q is split
//    into triangles 2q = (0,1,2) and 2q+1 = (0,2,3) of its corners;
//  - mesh2d: z = 0, x right, y down, same length unit as mesh3d, upright;
//  - mesh3d carries texture_u, texture_v (MeshLab convention: v up) into the
//    reference image and `comment TextureFile <path relative to the PLY>`.
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/ply.h"
#include "common/raster.h"

namespace docunfold {

namespace fs = std::filesystem;

struct QuadGrid {
  int nx = 0;  // vertices per row
  int ny = 0;  // rows
  int NumVertices() const { return nx * ny; }
  int NumQuads() const { return (nx - 1) * (ny - 1); }
  int Index(int row, int col) const { return row * nx + col; }
  // Corners of quad q in the order (r,c) (r,c+1) (r+1,c+1) (r+1,c).
  std::array<int, 4> Quad(int q) const;
  // Triangle t: 2q holds quad q's corners 0 1 2, 2q+1 its corners 0 2 3.
  Triangle TriangleOf(int t) const;
  std::vector<std::vector<int>> Faces() const;
  // Triangles 2q and 2q+1 of every quad q (see the file contract above).
  std::vector<Triangle> Triangles() const;
};

struct MeshPair {
  QuadGrid grid;
  std::vector<Eigen::Vector3d> mesh3d;  // M
  std::vector<Eigen::Vector2d> mesh2d;  // M' (z = 0 implied)
};

// A point on the meshes: triangle index (see QuadGrid::Triangles) and
// barycentric coordinates of its three corners.
struct SurfacePoint {
  int triangle = -1;
  Eigen::Vector3d bary = Eigen::Vector3d::Zero();
};

Eigen::Vector3d PointOnMesh3d(const MeshPair& m, const SurfacePoint& p);
Eigen::Vector2d PointOnMesh2d(const MeshPair& m, const SurfacePoint& p);

// Reads mesh3d.ply and mesh2d.ply of a folder; checks that both are the same
// grid (throws InputError naming the file and the problem).
MeshPair ReadMeshPair(const fs::path& dir);

struct MeshPairWriteOptions {
  // Reference image (for texture coordinates and MeshLab's TextureFile
  // comment) and its camera; both optional.
  std::optional<PinholeCamera> reference_camera;
  fs::path reference_image;           // absolute or relative to cwd
  std::vector<std::string> comments;  // provenance lines
};

// Writes mesh3d.ply and mesh2d.ply (binary, atomically) into `dir`.
void WriteMeshPair(const fs::path& dir, const MeshPair& m,
                   const MeshPairWriteOptions& options = {});

// Where the viewing ray of `pixel` meets the plane of the triangle with
// corners `world` (world coordinates): (u, v, s) with
// a + u (b - a) + v (c - a) = s K^-1 (x, y, 1) in the camera's frame; s > 0
// in front of the camera. Not finite when the ray runs along the plane.
Eigen::Vector3d RayOnTrianglePlane(const PinholeCamera& camera,
                                   const std::array<Eigen::Vector3d, 3>& world,
                                   const Eigen::Vector2d& pixel);

// Which point of M each pixel of the reference camera sees: a face index of
// M in the camera (PixelFaceIndex), built once and then queried for any
// number of pixels.
class PixelToSurface {
 public:
  // `scale` < 1 indexes a smaller face-id image (the barycentrics stay
  // exact: they come from the ray-plane intersection; only which triangle a
  // pixel near a triangle border belongs to is decided more coarsely).
  PixelToSurface(const MeshPair& m, const PinholeCamera& camera, double scale = 1.0);
  // The surface point seen at a (sub)pixel: the triangle of the nearest
  // pixel centre, with exact barycentrics of the viewing ray's intersection
  // with that triangle's plane. nullopt off the mesh.
  std::optional<SurfacePoint> Lookup(const Eigen::Vector2d& pixel) const;
  // Like Lookup, but when the pixel's ray misses M it takes the triangle of
  // the nearest pixel within `radius` pixels that sees M (its barycentrics
  // then extrapolate that triangle's plane a little): for samples on the
  // page's outline, half of whose pixel lies off the page.
  std::optional<SurfacePoint> LookupNear(const Eigen::Vector2d& pixel, double radius) const;
  // The triangle seen at pixel centre (x, y) of the scaled image; -1 off M.
  int FaceAt(int x, int y) const { return face_(x, y); }

 private:
  // Exact barycentrics of the pixel's viewing ray in triangle f's plane.
  std::optional<SurfacePoint> OnTriangle(int f, const Eigen::Vector2d& pixel) const;

  const MeshPair& mesh_;
  PinholeCamera camera_;
  std::vector<Triangle> triangles_;
  double scale_ = 1.0;
  PixelFaceIndex face_;
};

}  // namespace docunfold
