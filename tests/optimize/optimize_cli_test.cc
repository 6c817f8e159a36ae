// optimize on an analytic curled sheet (no data set needed): points of the
// table beside the page, outside the document region, change nothing.
#include <gtest/gtest.h>

#include "common/grid_mesh.h"
#include "common/page_files.h"
#include "tests/init-mesh/work_fixture.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

std::string OptimizeCommand(const fs::path& work, const fs::path& points, const fs::path& out) {
  return Quote(StageBinary("optimize").string()) + " --sfm " + Quote((work / "10_sfm").string()) +
         " --boundary " + Quote((work / "20_boundary").string()) + " --features " +
         Quote((work / "features.json").string()) + " --init " +
         Quote((work / "40_init").string()) + " --points " + Quote(points.string()) +
         " --out " + Quote(out.string()) + " --rounds 2 --no-scene 2>&1";
}

TEST(OptimizeCli, PointsOutsideTheDocumentRegionAreNotFitted) {
  TempDir dir;
  WriteSyntheticWork(dir.path(), 1500);
  ASSERT_EQ(RunCommand(InitMeshCommand(dir.path(), "--grid 8x12")).exit_code, 0);
  WriteJsonAtomic(dir / "features.json",
                  {{"format", "docunfold.features"}, {"version", 1}, {"segments", Json::array()}});
  // The table: a plane just behind the sheet, sampled all round it; the
  // points that project outside the page's outline are added.
  const CameraSet cameras = ReadCameras(dir / "10_sfm/cameras.json");
  const PinholeCamera& cam = *cameras.Find(cameras.reference);
  const cv::Mat1b region = ContourRegion(ReadBoundary(dir / "20_boundary/boundary.json"), 8);
  PlyData cloud = ReadPly(dir / "10_sfm/points.ply");
  const size_t page_points = cloud.vertices.size();
  double far = 0;
  for (const auto& p : cloud.vertices) far = std::max(far, cam.CamFromWorld(p).z());
  int table = 0;
  for (int v = 0; v < cam.height; v += 6)
    for (int u = 0; u < cam.width; u += 6) {
      if (region(v, u)) continue;
      cloud.vertices.push_back(cam.RayDirection(Eigen::Vector2d(u, v)) * (far + 0.01) /
                               cam.RayDirection(Eigen::Vector2d(u, v)).z());
      ++table;
    }
  cloud.colors.assign(cloud.vertices.size(), {90, 90, 90});
  WritePly(dir / "with_table.ply", cloud);
  ASSERT_GT(table, 1000);

  const CommandResult page = RunCommand(
      OptimizeCommand(dir.path(), dir / "10_sfm/points.ply", dir / "page"));
  ASSERT_EQ(page.exit_code, 0) << page.output;
  const CommandResult both = RunCommand(
      OptimizeCommand(dir.path(), dir / "with_table.ply", dir / "both"));
  ASSERT_EQ(both.exit_code, 0) << both.output;
  EXPECT_EQ(ReadJsonFile(dir / "both/log.json")["points_in_region"].get<size_t>(), page_points);
  const MeshPair a = ReadMeshPair(dir / "page"), b = ReadMeshPair(dir / "both");
  ASSERT_EQ(a.mesh3d.size(), b.mesh3d.size());
  for (size_t i = 0; i < a.mesh3d.size(); ++i)
    ASSERT_LT((a.mesh3d[i] - b.mesh3d[i]).norm(), 1e-9) << i;
}

}  // namespace
}  // namespace docunfold::testing
