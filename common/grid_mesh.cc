#include "common/grid_mesh.h"

#include <algorithm>
#include <cmath>

#include "common/errors.h"

namespace docunfold {

std::array<int, 4> QuadGrid::Quad(int q) const {
  const int r = q / (nx - 1), c = q % (nx - 1);
  return {Index(r, c), Index(r, c + 1), Index(r + 1, c + 1), Index(r + 1, c)};
}

std::vector<std::vector<int>> QuadGrid::Faces() const {
  std::vector<std::vector<int>> faces;
  faces.reserve(NumQuads());
  for (int q = 0; q < NumQuads(); ++q) {
    const auto c = Quad(q);
    faces.push_back({c[0], c[1], c[2], c[3]});
  }
  return faces;
}

Triangle QuadGrid::TriangleOf(int t) const {
  const auto c = Quad(t / 2);
  return t % 2 == 0 ? Triangle{c[0], c[1], c[2]} : Triangle{c[0], c[2], c[3]};
}

std::vector<Triangle> QuadGrid::Triangles() const {
  std::vector<Triangle> tris;
  tris.reserve(2 * NumQuads());
  for (int q = 0; q < NumQuads(); ++q) {
    const auto c = Quad(q);
    tris.push_back({c[0], c[1], c[2]});
    tris.push_back({c[0], c[2], c[3]});
  }
  return tris;
}

namespace {

QuadGrid GridOf(const PlyData& ply, const fs::path& path) {
  auto size = ply.GridSize();
  if (!size)
    throw InputError(path.string() +
                     ": no valid 'comment grid NX NY' line matching the vertex count");
  QuadGrid grid{(*size)[0], (*size)[1]};
  if (ply.faces.size() != size_t(grid.NumQuads()))
    throw InputError(path.string() + ": expected " + std::to_string(grid.NumQuads()) +
                     " quads for a " + std::to_string(grid.nx) + "x" + std::to_string(grid.ny) +
                     " grid, found " + std::to_string(ply.faces.size()) + " faces");
  return grid;
}

}  // namespace

Eigen::Vector3d PointOnMesh3d(const MeshPair& m, const SurfacePoint& p) {
  const Triangle t = m.grid.TriangleOf(p.triangle);
  return p.bary[0] * m.mesh3d[t[0]] + p.bary[1] * m.mesh3d[t[1]] + p.bary[2] * m.mesh3d[t[2]];
}

Eigen::Vector2d PointOnMesh2d(const MeshPair& m, const SurfacePoint& p) {
  const Triangle t = m.grid.TriangleOf(p.triangle);
  return p.bary[0] * m.mesh2d[t[0]] + p.bary[1] * m.mesh2d[t[1]] + p.bary[2] * m.mesh2d[t[2]];
}

MeshPair ReadMeshPair(const fs::path& dir) {
  const fs::path p3 = dir / "mesh3d.ply", p2 = dir / "mesh2d.ply";
  PlyData m3 = ReadPly(p3);
  PlyData m2 = ReadPly(p2);
  MeshPair m;
  m.grid = GridOf(m3, p3);
  const QuadGrid g2 = GridOf(m2, p2);
  if (g2.nx != m.grid.nx || g2.ny != m.grid.ny)
    throw InputError(p2.string() + ": grid " + std::to_string(g2.nx) + "x" + std::to_string(g2.ny) +
                     " differs from mesh3d.ply's " + std::to_string(m.grid.nx) + "x" +
                     std::to_string(m.grid.ny));
  const auto faces = m.grid.Faces();
  if (m3.faces != faces)
    throw InputError(p3.string() + ": faces are not the row-major quads of the grid");
  if (m2.faces != faces)
    throw InputError(p2.string() + ": faces are not the row-major quads of the grid");
  m.mesh3d = m3.vertices;
  for (const Eigen::Vector3d& v : m2.vertices) {
    if (std::abs(v.z()) > 1e-9 * (1 + v.head<2>().norm()))
      throw InputError(p2.string() + ": the flat mesh must lie in z = 0");
    m.mesh2d.push_back(v.head<2>());
  }
  return m;
}

void WriteMeshPair(const fs::path& dir, const MeshPair& m, const MeshPairWriteOptions& options) {
  PlyData m3, m2;
  m3.vertices = m.mesh3d;
  for (const Eigen::Vector2d& v : m.mesh2d) m2.vertices.emplace_back(v.x(), v.y(), 0.0);
  m3.faces = m2.faces = m.grid.Faces();
  for (PlyData* p : {&m3, &m2}) {
    p->comments = options.comments;
    p->SetGridSize(m.grid.nx, m.grid.ny);
  }
  m3.comments.insert(m3.comments.begin(), "docunfold mesh3d: M, the page in the world frame");
  m2.comments.insert(m2.comments.begin(),
                     "docunfold mesh2d: M', the flat page (z = 0, x right, y down)");
  if (options.reference_camera) {
    const PinholeCamera& cam = *options.reference_camera;
    std::vector<double> u, v;
    for (const Eigen::Vector3d& x : m.mesh3d) {
      const Eigen::Vector2d px = cam.Project(x);
      u.push_back((px.x() + 0.5) / cam.width);
      v.push_back(1.0 - (px.y() + 0.5) / cam.height);
    }
    m3.SetProperty("texture_u", u);
    m3.SetProperty("texture_v", v);
    if (!options.reference_image.empty()) {
      fs::path rel = fs::absolute(options.reference_image).lexically_relative(fs::absolute(dir));
      m3.comments.push_back("TextureFile " + rel.generic_string());
    }
  }
  WritePly(dir / "mesh3d.ply", m3);
  WritePly(dir / "mesh2d.ply", m2);
}

PixelToSurface::PixelToSurface(const MeshPair& m, const PinholeCamera& camera, double scale)
    : mesh_(m),
      camera_(camera),
      triangles_(m.grid.Triangles()),
      scale_(scale),
      face_(MeshFaceIndex(camera_, m.mesh3d, triangles_, scale_)) {}

std::optional<SurfacePoint> PixelToSurface::Lookup(const Eigen::Vector2d& pixel) const {
  const int x = int(std::lround((pixel.x() + 0.5) * scale_ - 0.5));
  const int y = int(std::lround((pixel.y() + 0.5) * scale_ - 0.5));
  const int f = face_(x, y);
  if (f < 0) return std::nullopt;
  return OnTriangle(f, pixel);
}

std::optional<SurfacePoint> PixelToSurface::LookupNear(const Eigen::Vector2d& pixel,
                                                       double radius) const {
  if (auto p = Lookup(pixel)) return p;
  const int cx = int(std::lround((pixel.x() + 0.5) * scale_ - 0.5));
  const int cy = int(std::lround((pixel.y() + 0.5) * scale_ - 0.5));
  const int r = std::max(1, int(std::ceil(radius * scale_)));
  int best = -1;
  double best_d2 = 1e300;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const int x = cx + dx, y = cy + dy;
      const double d2 = dx * dx + dy * dy;
      if (d2 > double(r) * r || d2 >= best_d2) continue;
      const int f = face_(x, y);
      if (f < 0) continue;
      best = f;
      best_d2 = d2;
    }
  if (best < 0) return std::nullopt;
  return OnTriangle(best, pixel);
}

Eigen::Vector3d RayOnTrianglePlane(const PinholeCamera& camera,
                                   const std::array<Eigen::Vector3d, 3>& world,
                                   const Eigen::Vector2d& pixel) {
  const Eigen::Vector3d a = camera.CamFromWorld(world[0]);
  const Eigen::Vector3d b = camera.CamFromWorld(world[1]);
  const Eigen::Vector3d c = camera.CamFromWorld(world[2]);
  const Eigen::Vector3d d = camera.CamRay(pixel);
  // Solve a + u (b - a) + v (c - a) = s d.
  Eigen::Matrix3d A;
  A << b - a, c - a, -d;
  return A.colPivHouseholderQr().solve(-a);
}

std::optional<SurfacePoint> PixelToSurface::OnTriangle(int f, const Eigen::Vector2d& pixel) const {
  // Intersect the pixel's viewing ray with the triangle's plane.
  const Triangle& t = triangles_[f];
  const Eigen::Vector3d sol = RayOnTrianglePlane(
      camera_, {mesh_.mesh3d[t[0]], mesh_.mesh3d[t[1]], mesh_.mesh3d[t[2]]}, pixel);
  SurfacePoint p;
  p.triangle = f;
  p.bary = Eigen::Vector3d(1 - sol[0] - sol[1], sol[0], sol[1]);
  if (!p.bary.allFinite()) return std::nullopt;
  return p;
}

}  // namespace docunfold
