// init-mesh on every data set with ground truth: 10_sfm from the truth with
// noise (0.2 % of the diagonal) and 3 % outliers, the true page outline as
// boundary. One run of the stage per data set is shared by the checks.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <chrono>
#include <cstdio>
#include <memory>
#include <regex>

#include "common/grid_mesh.h"
#include "common/isometry/metrics.h"
#include "common/json_io.h"
#include "tests/init-mesh/work_fixture.h"
#include "tests/isometry/test_meshes.h"
#include "tests/support/test_support.h"
#include "tests/support/truth_frame.h"

namespace docunfold::testing {
namespace {

struct TruthCase {
  fs::path set;
  std::string reference;
  std::unique_ptr<TempDir> dir;
  GroundTruth gt;
  double diagonal = 0;  // page diagonal in the reference frame
  MeshPair truth;       // true M and M' in the reference frame
  CommandResult run;
  double seconds = 0;
};

// 10_sfm and 20_boundary from the truth of `set`, then the stage, timed.
TruthCase Prepare(const fs::path& set) {
  TruthCase c;
  c.set = set;
  auto gt = LoadGroundTruth(set);
  if (!gt) return c;
  c.gt = std::move(*gt);
  c.reference = ChooseReferenceView(c.gt);
  c.dir = std::make_unique<TempDir>();
  SfmFromTruthOptions so;
  so.num_points = 5000;
  so.noise = 0.002;  // 0.2 % of the page diagonal
  so.outlier_fraction = 0.03;
  WriteWorkFromTruth(c.gt, c.reference, c.dir->path(), so);
  c.diagonal = c.gt.Diagonal() * ReferenceFrame(c.gt, c.reference).scale;
  c.truth = TrueMeshPair(c.gt, c.reference);
  const auto start = std::chrono::steady_clock::now();
  c.run = RunCommand(InitMeshCommand(c.dir->path()));
  c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return c;
}

void CheckMeshNearTruthAndIsometric(const TruthCase& c) {
  ASSERT_EQ(c.run.exit_code, 0) << c.set << "\n" << c.run.output;
  const MeshPair m = ReadMeshPair(c.dir->path() / "40_init");
  const DistanceStats to_truth = SurfaceDistance(m, c.truth);
  const DistanceStats from_truth = SurfaceDistance(c.truth, m);
  const auto iso = isometry::IsometryEdgeError(m);
  EXPECT_LT(to_truth.mean, 0.01 * c.diagonal) << c.set;
  // M covers the page: the truth is near M too (when the whole page is in
  // the reference view).
  const Json boundary = ReadJsonFile(c.dir->path() / "20_boundary/boundary.json");
  bool whole_page = true;
  for (const auto& side : boundary["sides"]) whole_page = whole_page && side["real"].get<bool>();
  if (whole_page) {
    EXPECT_LT(from_truth.mean, 0.01 * c.diagonal) << c.set;
  }
  EXPECT_LT(iso.mean, 0.005) << c.set;
  EXPECT_EQ(m.grid.NumQuads(), 600) << c.set;
  const Json init = ReadJsonFile(c.dir->path() / "40_init/init.json");
  std::printf(
      "%-6s ref %-12s M->truth mean %.3f%% max %.3f%%, truth->M mean %.3f%% of diagonal; "
      "isometry edge error mean %.3f%% max %.2f%%; %zu refine iterations; %.2f s "
      "(depth %.3f grid %.3f unfold %.3f refine %.3f upright %.3f)\n",
      c.set.filename().c_str(), c.reference.c_str(), 100 * to_truth.mean / c.diagonal,
      100 * to_truth.max / c.diagonal, 100 * from_truth.mean / c.diagonal, 100 * iso.mean,
      100 * iso.max, init["refine"]["iterations"].size(), c.seconds,
      init["timings_s"]["depth"].get<double>(), init["timings_s"]["grid"].get<double>(),
      init["timings_s"]["unfold"].get<double>(), init["timings_s"]["refine"].get<double>(),
      init["timings_s"]["upright"].get<double>());
}

// M' is upright: after a rigid 2D alignment (no reflection) with the true
// flat page, the rotation is small and the shapes agree.
void CheckFlatMeshUprightAndTrue(const TruthCase& c) {
  ASSERT_EQ(c.run.exit_code, 0) << c.set;
  const MeshPair m = ReadMeshPair(c.dir->path() / "40_init");
  // The true flat position of each vertex of M: the closest point on the
  // true M, carried to the true M'.
  isometry::TriangleMeshIndex index(c.truth.mesh3d, c.truth.grid.Triangles());
  Eigen::Matrix2Xd ours(2, m.mesh3d.size()), theirs(2, m.mesh3d.size());
  for (size_t i = 0; i < m.mesh3d.size(); ++i) {
    const auto cp = index.Closest(m.mesh3d[i]);
    theirs.col(i) = PointOnMesh2d(c.truth, {cp->triangle, cp->bary});
    ours.col(i) = m.mesh2d[i];
  }
  const Eigen::Matrix3d t = Eigen::umeyama(ours, theirs, false);
  const double angle = std::atan2(t(1, 0), t(0, 0)) * 180 / M_PI;
  EXPECT_GT((t.topLeftCorner<2, 2>().determinant()), 0) << c.set << ": M' is mirrored";
  EXPECT_LT(std::abs(angle), 3.0) << c.set;
  double err = 0;
  for (int i = 0; i < ours.cols(); ++i)
    err += ((t.topLeftCorner<2, 2>() * ours.col(i) + t.topRightCorner<2, 1>()) - theirs.col(i))
               .norm() /
           ours.cols();
  EXPECT_LT(err, 0.01 * c.diagonal) << c.set;
  // Upright convention: M' starts at (0, 0), top-left.
  Eigen::Vector2d lo(1e9, 1e9);
  for (const auto& v : m.mesh2d) lo = lo.cwiseMin(v);
  EXPECT_LT(lo.norm(), 1e-9) << c.set;
  std::printf("%-6s M' rotation vs truth %.2f deg, mean flat error %.3f%% of diagonal\n",
              c.set.filename().c_str(), angle, 100 * err / c.diagonal);
}

// An independent PLY reader (assimp) opens both meshes with the right counts.
void CheckPlysOpenInAssimp(const TruthCase& c) {
  ASSERT_EQ(c.run.exit_code, 0);
  for (const char* name : {"mesh3d.ply", "mesh2d.ply"}) {
    const fs::path ply = c.dir->path() / "40_init" / name;
    const CommandResult info = RunCommand("assimp info " + Quote(ply.string()) + " 2>&1");
    ASSERT_EQ(info.exit_code, 0) << info.output;
    std::smatch v, f;
    ASSERT_TRUE(std::regex_search(info.output, v, std::regex(R"(Vertices:\s+(\d+))")))
        << info.output;
    ASSERT_TRUE(std::regex_search(info.output, f, std::regex(R"(Faces:\s+(\d+))"))) << info.output;
    // 21 x 31 vertices, 600 quads (assimp may triangulate: 600 or 1200).
    EXPECT_EQ(std::stoi(v[1]) >= 651, true) << info.output;
    const int faces = std::stoi(f[1]);
    EXPECT_TRUE(faces == 600 || faces == 1200) << info.output;
  }
  const PlyData ply = ReadPly(c.dir->path() / "40_init/mesh3d.ply");
  EXPECT_EQ(ply.vertices.size(), 651u);
  EXPECT_NE(ply.FindProperty("texture_u"), nullptr);
  EXPECT_EQ(ply.CommentValue("TextureFile").value_or(""), "../10_sfm/reference.png");
}

void CheckInitJson(const TruthCase& c) {
  const fs::path json = c.dir->path() / "40_init/init.json";
  const CommandResult v = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                                     Quote(json.string()) + " 2>&1");
  EXPECT_EQ(v.exit_code, 0) << c.set << "\n" << v.output;
  const Json doc = ReadJsonFile(json);
  EXPECT_EQ(doc["grid"]["source"], "coons") << c.set;
  const Json boundary = ReadJsonFile(c.dir->path() / "20_boundary/boundary.json");
  std::string real;
  for (const char* side : {"top", "right", "bottom", "left"})
    if (boundary["sides"][side]["real"].get<bool>())
      real += std::string(real.empty() ? "" : ", ") + side;
  EXPECT_EQ(doc["upright"]["from"], "real sides: " + real) << c.set;
  EXPECT_GT(doc["points"]["inliers"].get<int>(), 4000) << c.set;
  EXPECT_LT(doc["points"]["inliers"].get<int>(), 5150) << c.set;
}

// One test (one run of the stage per data set, every check on it): ctest
// runs each test in its own process, so separate tests would redo the runs.
TEST(InitMeshOnTruth, EveryDataSet) {
  const auto sets = DataSetsWithGroundTruth();
  if (sets.empty()) GTEST_SKIP() << "no data sets with ground truth";
  bool first = true;
  for (const fs::path& set : sets) {
    SCOPED_TRACE(set.string());
    const TruthCase c = Prepare(set);
    ASSERT_TRUE(c.dir) << "cannot load the ground truth of " << set;
    ASSERT_EQ(c.run.exit_code, 0) << c.run.output;
    CheckMeshNearTruthAndIsometric(c);
    CheckFlatMeshUprightAndTrue(c);
    CheckInitJson(c);
    if (first) CheckPlysOpenInAssimp(c);
    first = false;
  }
}

}  // namespace
}  // namespace docunfold::testing
