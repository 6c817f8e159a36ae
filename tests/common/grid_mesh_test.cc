#include "common/grid_mesh.h"

#include <gtest/gtest.h>

#include "common/errors.h"
#include "tests/support/test_support.h"

namespace docunfold {
namespace {

// A gently curved 5x4 grid one unit in front of an identity camera.
MeshPair CurvedSheet() {
  MeshPair m;
  m.grid = {5, 4};
  for (int r = 0; r < m.grid.ny; ++r)
    for (int c = 0; c < m.grid.nx; ++c) {
      const double x = -0.4 + 0.2 * c, y = -0.3 + 0.2 * r;
      m.mesh3d.emplace_back(x, y, 1.0 + 0.1 * x * x);
      m.mesh2d.emplace_back(0.2 * c, 0.2 * r);
    }
  return m;
}

PinholeCamera Camera() {
  PinholeCamera cam;
  cam.width = 640;
  cam.height = 480;
  cam.K << 500, 0, 319.5, 0, 500, 239.5, 0, 0, 1;
  return cam;
}

TEST(GridMesh, TrianglesSplitEachQuadIntoTwo) {
  QuadGrid g{3, 2};
  EXPECT_EQ(g.NumQuads(), 2);
  auto tris = g.Triangles();
  ASSERT_EQ(tris.size(), 4u);
  EXPECT_EQ(tris[0], (Triangle{0, 1, 4}));
  EXPECT_EQ(tris[1], (Triangle{0, 4, 3}));
  EXPECT_EQ(g.Faces()[1], (std::vector<int>{1, 2, 5, 4}));
}

TEST(GridMesh, WriteAndReadKeepTheGridAndTextureCoordinates) {
  testing::TempDir dir;
  MeshPair m = CurvedSheet();
  MeshPairWriteOptions options;
  options.reference_camera = Camera();
  options.reference_image = dir / "10_sfm/reference.png";
  WriteMeshPair(dir / "40_init", m, options);
  MeshPair back = ReadMeshPair(dir / "40_init");
  EXPECT_EQ(back.grid.nx, 5);
  EXPECT_EQ(back.grid.ny, 4);
  for (size_t i = 0; i < m.mesh3d.size(); ++i) {
    EXPECT_LT((back.mesh3d[i] - m.mesh3d[i]).norm(), 1e-6);
    EXPECT_LT((back.mesh2d[i] - m.mesh2d[i]).norm(), 1e-6);
  }
  PlyData ply = ReadPly(dir / "40_init/mesh3d.ply");
  EXPECT_EQ(ply.CommentValue("TextureFile").value_or(""), "../10_sfm/reference.png");
  ASSERT_NE(ply.FindProperty("texture_u"), nullptr);
  // The centre vertex (x = 0) projects to the principal point column.
  EXPECT_NEAR(ply.FindProperty("texture_u")->values[m.grid.Index(1, 2)], 0.5, 1e-6);
}

TEST(GridMesh, MismatchedGridsAreRejected) {
  testing::TempDir dir;
  MeshPair m = CurvedSheet();
  WriteMeshPair(dir.path(), m);
  PlyData flat = ReadPly(dir / "mesh2d.ply");
  flat.SetGridSize(4, 5);
  WritePly(dir / "mesh2d.ply", flat);
  try {
    ReadMeshPair(dir.path());
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mesh2d.ply: grid 4x5 differs"), std::string::npos)
        << e.what();
  }
}

TEST(GridMesh, PixelsMapOntoBothMeshes) {
  MeshPair m = CurvedSheet();
  const PinholeCamera cam = Camera();
  PixelToSurface map(m, cam);
  // A vertex's own pixel maps back onto that vertex on both meshes.
  const int v = m.grid.Index(2, 1);
  auto p = map.Lookup(cam.Project(m.mesh3d[v]));
  ASSERT_TRUE(p);
  EXPECT_LT((PointOnMesh3d(m, *p) - m.mesh3d[v]).norm(), 1e-9);
  EXPECT_LT((PointOnMesh2d(m, *p) - m.mesh2d[v]).norm(), 1e-9);
  // Any pixel's point lies on its viewing ray.
  const Eigen::Vector2d px(300.3, 250.7);
  p = map.Lookup(px);
  ASSERT_TRUE(p);
  EXPECT_LT((cam.Project(PointOnMesh3d(m, *p)) - px).norm(), 1e-6);
  EXPECT_FALSE(map.Lookup({2, 2}));
}

}  // namespace
}  // namespace docunfold
