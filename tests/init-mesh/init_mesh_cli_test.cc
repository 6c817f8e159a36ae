// init-mesh on awkward inputs: an analytic curled sheet in front of a
// camera (no data set needed), missing and corrupt files, points on part of
// the page, an unusable boundary.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <regex>

#include "common/camera.h"
#include "common/grid_mesh.h"
#include "common/isometry/metrics.h"
#include "common/json_io.h"
#include "tests/init-mesh/work_fixture.h"
#include "tests/isometry/test_meshes.h"
#include "tests/support/test_support.h"
#include "tests/support/truth_frame.h"

namespace docunfold::testing {
namespace {

// --- awkward inputs (an analytic sheet; no data needed) ----------------------

TEST(InitMeshCli, SyntheticSheetIsReconstructed) {
  TempDir dir;
  const MeshPair truth = WriteSyntheticWork(dir.path());
  const CommandResult r = RunCommand(InitMeshCommand(dir.path(), "--grid 8x12"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const MeshPair m = ReadMeshPair(dir / "40_init");
  EXPECT_EQ(m.grid.NumQuads(), 96);
  // The long side (0.297) runs along the grid rows: 12 quads there.
  EXPECT_EQ(std::max(m.grid.nx, m.grid.ny), 13);
  const double size = isometry::ModelSize(truth);
  EXPECT_LT(SurfaceDistance(m, truth).mean, 0.01 * size);
  EXPECT_LT(isometry::IsometryEdgeError(m).mean, 0.005);
}

// A folded, tilted page whose margins have no points (as printed pages):
// the default depth model and fairness carry each panel out to the edge.
// The paper's depth model is printed for comparison (on exact, dense points
// like these it does as well; the difference shows on SfM clouds with
// gaps).
TEST(InitMeshCli, BlankMarginsContinueTheirPanels) {
  TempDir ours, paper;
  const MeshPair truth = WriteFoldedPageWithMarginsWork(ours.path(), 40, 30, 0.15);
  WriteFoldedPageWithMarginsWork(paper.path(), 40, 30, 0.15);
  const CommandResult a = RunCommand(InitMeshCommand(ours.path()));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const CommandResult b = RunCommand(InitMeshCommand(paper.path(), "--depth-model average"));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const double size = isometry::ModelSize(truth);
  const auto with = SurfaceDistance(ReadMeshPair(ours / "40_init"), truth);
  const auto without = SurfaceDistance(ReadMeshPair(paper / "40_init"), truth);
  std::printf(
      "[init] blank margins: mean distance %.3f %% of the model size (paper's settings "
      "%.3f %%)\n",
      100 * with.mean / size, 100 * without.mean / size);
  EXPECT_LT(with.mean, 0.002 * size);
  EXPECT_LT(isometry::IsometryEdgeError(ReadMeshPair(ours / "40_init")).mean, 0.005);
}

// A zig-zag folded page whose print lies in strips along two sides, the folds
// crossing blank paper between (set07's receipt): the page's outline in 3D
// (outline points) gives the blank band its panels; the points alone cannot
// tell a panel's blank middle from a bulge. init.json says what was used.
TEST(InitMeshCli, TheOutlineShapesBlankPaperBetweenFolds) {
  TempDir with, without;
  const MeshPair truth = WriteZigZagWithBlankBandWork(with.path(), 60, 0.2);
  WriteZigZagWithBlankBandWork(without.path(), 60, 0.2);
  const CommandResult a = RunCommand(InitMeshCommand(with.path(), "--max-iterations 0"));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const CommandResult b =
      RunCommand(InitMeshCommand(without.path(), "--max-iterations 0 --no-outline-prior"));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const double size = isometry::ModelSize(truth);
  const auto prior = SurfaceDistance(ReadMeshPair(with / "40_init"), truth);
  const auto points = SurfaceDistance(ReadMeshPair(without / "40_init"), truth);
  std::printf(
      "[init] zig-zag, blank band: mean distance of the lifted grid %.3f %% of the model "
      "size with the outline prior, %.3f %% from the points alone\n",
      100 * prior.mean / size, 100 * points.mean / size);
  EXPECT_LT(prior.mean, 0.5 * points.mean);
  EXPECT_LT(prior.mean, 0.003 * size);
  const Json report = ReadJsonFile(with / "40_init/init.json");
  EXPECT_TRUE(report["outline_prior"]["used"].get<bool>());
  EXPECT_EQ(report["outline_prior"]["sides_measured"].get<int>(), 4);
  EXPECT_FALSE(ReadJsonFile(without / "40_init/init.json")["outline_prior"]["used"].get<bool>());
}

// A page folded along its diagonal, one half standing edge-on to the
// reference photo: the reference outline is a triangle. The other photos'
// pages tell which points are the page's; M is built from them and covers
// the whole page. Without those photos, M on the triangle reaches onto the
// standing half only as far as the refinement pulls it.
TEST(InitMeshCli, ATriangularReferenceOutlineStillGivesTheWholePage) {
  TempDir with, without;
  const MeshPair truth = WriteDiagonalFoldWork(with.path());
  WriteDiagonalFoldWork(without.path());
  fs::remove_all(without / "20_boundary/views");
  const CommandResult a = RunCommand(InitMeshCommand(with.path()));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  EXPECT_NE(a.output.find("mesh built from the points of every photo"), std::string::npos)
      << a.output;
  const CommandResult b = RunCommand(InitMeshCommand(without.path()));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const Json report = ReadJsonFile(with / "40_init/init.json");
  EXPECT_EQ(report["grid"]["source"], "page_points");
  EXPECT_GT(report["page_points"]["off_reference_mesh"].get<double>(), 0.01);
  const MeshPair m = ReadMeshPair(with / "40_init");
  const MeshPair flat_half = ReadMeshPair(without / "40_init");
  const double size = isometry::ModelSize(truth);
  const auto page_to_m = SurfaceDistance(truth, m);
  const auto m_to_page = SurfaceDistance(m, truth);
  const auto page_to_half = SurfaceDistance(truth, flat_half);
  auto flat_area = [](const MeshPair& pair) {  // of M', over the page's
    double sum = 0;
    for (const Triangle& t : pair.grid.Triangles()) {
      const Eigen::Vector2d e1 = pair.mesh2d[t[1]] - pair.mesh2d[t[0]];
      const Eigen::Vector2d e2 = pair.mesh2d[t[2]] - pair.mesh2d[t[0]];
      sum += 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
    }
    return sum / (0.21 * 0.297);
  };
  const double area = flat_area(m);
  const double half_area = flat_area(flat_half);
  std::printf(
      "[init] diagonal fold, triangular reference outline: page to M %.2f %% (max %.2f %%), M "
      "to page %.2f %% of the model size, M' area %.3f of the page; from the reference "
      "outline alone page to M %.2f %% (max %.2f %%), area %.3f\n",
      100 * page_to_m.mean / size, 100 * page_to_m.max / size, 100 * m_to_page.mean / size, area,
      100 * page_to_half.mean / size, 100 * page_to_half.max / size, half_area);
  EXPECT_LT(page_to_m.mean, 0.005 * size);
  EXPECT_LT(page_to_m.max, 0.03 * size);
  EXPECT_LT(m_to_page.mean, 0.005 * size);
  EXPECT_NEAR(area, 1.0, 0.05);
  // On the triangle alone the standing half's tip is missing.
  EXPECT_GT(page_to_half.max, 0.05 * size);
  EXPECT_LT(half_area, 0.93);
  EXPECT_LT(isometry::IsometryEdgeError(m).mean, 0.01);
}

// init-mesh on a receipt whose last fifth stands at `fold_deg`
// (WriteStandingEndWork), with the end folds and with --no-end-fold.
struct EndFoldRuns {
  MeshPair truth, folded, smooth;
  Json report;  // init.json of the run with the end folds
};
EndFoldRuns RunWithAndWithoutEndFold(double fold_deg) {
  TempDir with, without;
  EndFoldRuns runs;
  runs.truth = WriteStandingEndWork(with.path(), fold_deg);
  WriteStandingEndWork(without.path(), fold_deg);
  const CommandResult a = RunCommand(InitMeshCommand(with.path()));
  EXPECT_EQ(a.exit_code, 0) << a.output;
  const CommandResult b = RunCommand(InitMeshCommand(without.path(), "--no-end-fold"));
  EXPECT_EQ(b.exit_code, 0) << b.output;
  runs.report = ReadJsonFile(with / "40_init/init.json");
  runs.folded = ReadMeshPair(with / "40_init");
  runs.smooth = ReadMeshPair(without / "40_init");
  return runs;
}

TEST(InitMeshCli, AnEndStandingUpIsFoldedFromTheOtherPhotosMasks) {
  const EndFoldRuns runs = RunWithAndWithoutEndFold(85);
  int kept = 0;
  for (const Json& fold : runs.report["end_folds"])
    if (fold["kept"].get<bool>()) {
      ++kept;
      EXPECT_EQ(fold["end"], "last_row") << fold.dump();
    }
  EXPECT_EQ(kept, 1) << runs.report["end_folds"].dump();
  const double size = isometry::ModelSize(runs.truth);
  const auto page_to_m = SurfaceDistance(runs.truth, runs.folded);
  const auto page_to_smooth = SurfaceDistance(runs.truth, runs.smooth);
  // M' of the pair may be scaled against the truth: compare its length with
  // its width.
  auto aspect = [](const MeshPair& pair) {
    Eigen::AlignedBox2d box;
    for (const Eigen::Vector2d& v : pair.mesh2d) box.extend(v);
    return box.sizes().maxCoeff() / box.sizes().minCoeff();
  };
  std::printf(
      "[init] receipt end standing at 85 deg: page to M %.2f %% (max %.2f %%) of the model size, "
      "M' %.3f as long as wide (page 2.5); without the fold %.2f %% (max %.2f %%), %.3f\n",
      100 * page_to_m.mean / size, 100 * page_to_m.max / size, aspect(runs.folded),
      100 * page_to_smooth.mean / size, 100 * page_to_smooth.max / size, aspect(runs.smooth));
  EXPECT_LT(page_to_m.mean, 0.5 * page_to_smooth.mean);
  EXPECT_LT(page_to_m.max, 0.5 * page_to_smooth.max);
  EXPECT_NEAR(aspect(runs.folded), 2.5, 0.1);
  EXPECT_LT(aspect(runs.smooth), 2.35);  // the standing end comes out short
}

TEST(InitMeshCli, AFlatEndWithoutPointsStaysFlat) {
  const EndFoldRuns runs = RunWithAndWithoutEndFold(0);
  const double size = isometry::ModelSize(runs.truth);
  const auto page_to_m = SurfaceDistance(runs.truth, runs.folded);
  const auto page_to_smooth = SurfaceDistance(runs.truth, runs.smooth);
  std::printf(
      "[init] flat receipt, last fifth without points: page to M %.2f %% (max %.2f %%) of the "
      "model size; without the end fold %.2f %% (max %.2f %%)\n",
      100 * page_to_m.mean / size, 100 * page_to_m.max / size, 100 * page_to_smooth.mean / size,
      100 * page_to_smooth.max / size);
  // The end without points comes out bent; the masks put it back in the
  // page's plane.
  EXPECT_LT(page_to_m.mean, 0.003 * size);
  EXPECT_LT(page_to_m.max, 0.02 * size);
  EXPECT_GT(page_to_smooth.max, 0.05 * size);
}

TEST(InitMeshCli, MissingOrCorruptFilesAreBadInput) {
  TempDir dir;
  WriteSyntheticWork(dir.path(), 400);
  {
    fs::rename(dir / "10_sfm/points.ply", dir / "points.ply");
    const CommandResult r = RunCommand(InitMeshCommand(dir.path()));
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find("points.ply"), std::string::npos) << r.output;
    fs::rename(dir / "points.ply", dir / "10_sfm/points.ply");
  }
  {
    WriteTextAtomic(dir / "10_sfm/cameras.json", "{\"format\": \"docunfold.cameras\", ");
    const CommandResult r = RunCommand(InitMeshCommand(dir.path()));
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find("cameras.json"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "40_init/init.json"));
  }
  TempDir dir2;
  WriteSyntheticWork(dir2.path(), 400);
  {
    WriteTextAtomic(dir2 / "20_boundary/mask.png", "not a png");
    const CommandResult r = RunCommand(InitMeshCommand(dir2.path()));
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find("mask.png"), std::string::npos) << r.output;
  }
  {
    WriteImageAtomic(dir2 / "20_boundary/mask.png", cv::Mat1b(480, 640, uchar(0)));
    const CommandResult r = RunCommand(InitMeshCommand(dir2.path()));
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find("empty document region"), std::string::npos) << r.output;
  }
  {
    WriteImageAtomic(dir2 / "20_boundary/mask.png", cv::Mat1b(100, 100, uchar(255)));
    const CommandResult r = RunCommand(InitMeshCommand(dir2.path()));
    EXPECT_EQ(r.exit_code, 3) << r.output;
  }
  {
    const CommandResult r = RunCommand(InitMeshCommand(dir2.path(), "--grid 20by30"));
    EXPECT_EQ(r.exit_code, 2) << r.output;
  }
}

// A third of the page without points is carried over with a warning (a
// panel of a fold that one other photo sees has none); points on less than
// half of the page are bad input, and the message says where they are missing.
TEST(InitMeshCli, PointsOnPartOfThePageNameTheMissingPart) {
  TempDir part;
  const MeshPair truth = WriteSyntheticWork(part.path(), 1500, 0.6);  // nothing on the right 40 %
  const CommandResult r = RunCommand(InitMeshCommand(part.path()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: no points in the right third"), std::string::npos) << r.output;
  const Json init = ReadJsonFile(part / "40_init/init.json");
  ASSERT_EQ(init["warnings"].size(), 1u) << init.dump();
  EXPECT_NE(init["warnings"][0].get<std::string>().find("right third"), std::string::npos);
  // The curl continues over the empty part: within 1 % of the model size of
  // the true sheet on average (measured 0.44 %).
  const MeshPair m = ReadMeshPair(part / "40_init");
  const double off = SurfaceDistance(m, truth).mean / isometry::ModelSize(truth);
  std::printf("[init] right 40 %% without points: mean distance %.3f %% of the model size\n",
              100 * off);
  EXPECT_LT(off, 0.01);

  TempDir strip;
  WriteSyntheticWork(strip.path(), 1500, 0.3);  // points on the left 30 % only
  const CommandResult r1 = RunCommand(InitMeshCommand(strip.path()));
  EXPECT_EQ(r1.exit_code, 3) << r1.output;
  EXPECT_NE(r1.output.find("3 of the page's 9 parts"), std::string::npos) << r1.output;
  EXPECT_NE(r1.output.find("right third"), std::string::npos) << r1.output;
  EXPECT_FALSE(fs::exists(strip / "40_init/mesh3d.ply"));

  TempDir few;
  WriteSyntheticWork(few.path(), 12);
  const CommandResult r2 = RunCommand(InitMeshCommand(few.path()));
  EXPECT_EQ(r2.exit_code, 3) << r2.output;
  EXPECT_NE(r2.output.find("inside the document region"), std::string::npos) << r2.output;
}

// boundary.json is read as every stage reads it: one that does not follow
// its schema is bad input, naming the file and the part.
TEST(InitMeshCli, MalformedBoundaryIsBadInput) {
  TempDir dir;
  WriteSyntheticWork(dir.path(), 400);
  Json doc = ReadJsonFile(dir / "20_boundary/boundary.json");
  doc["corners"] = Json::array({{10, 10}, {20, 20}});
  WriteJsonAtomic(dir / "20_boundary/boundary.json", doc);
  const CommandResult r = RunCommand(InitMeshCommand(dir.path()));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("boundary.json:/corners"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "40_init/init.json"));
}

// A boundary whose sides cannot carry a Coons patch (here the left side is
// a stub, cut off by the image border) gives a grid over the mask's bounding
// box, with a warning.
TEST(InitMeshCli, UnusableBoundaryFallsBackToTheMaskWithAWarning) {
  TempDir dir;
  const MeshPair truth = WriteSyntheticWork(dir.path());
  Json doc = ReadJsonFile(dir / "20_boundary/boundary.json");
  Json& left = doc["sides"]["left"];
  const Json first = left["points"][0];
  left["points"] = Json::array(
      {first, {first[0].get<double>(), first[1].get<double>() + 2}});  // 2 px: too short
  left["real"] = false;
  WriteJsonAtomic(dir / "20_boundary/boundary.json", doc);
  const CommandResult r = RunCommand(InitMeshCommand(dir.path(), "--grid 8x12"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: boundary unusable (the left side is too short"),
            std::string::npos)
      << r.output;
  const Json init = ReadJsonFile(dir / "40_init/init.json");
  EXPECT_EQ(init["grid"]["source"], "mask_bbox");
  // The real sides it still has are found on the bounding-box grid.
  const std::string from = init["upright"]["from"];
  EXPECT_EQ(from.rfind("real sides: ", 0), 0u) << from;
  EXPECT_EQ(from.find("left"), std::string::npos) << from;
  ASSERT_EQ(init["warnings"].size(), 1u);
  // The bounding-box grid reaches beyond the page; where it covers the page
  // it is still on the true surface.
  const MeshPair m = ReadMeshPair(dir / "40_init");
  EXPECT_LT(SurfaceDistance(truth, m).mean, 0.01 * isometry::ModelSize(truth));
}

}  // namespace
}  // namespace docunfold::testing
