// The render binary: outputs, flags, exit codes, no partial outputs.
#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/atomic_file.h"
#include "common/grid_mesh.h"
#include "common/json_io.h"
#include "common/ply.h"
#include "tests/render/render_fixtures.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

class RenderCli : public ::testing::Test {
 protected:
  // One scene on disk for every test (10_sfm, 20_boundary, 40_init).
  static void SetUpTestSuite() {
    scene_dir_ = std::make_unique<TempDir>();
    WriteScene(MakeScene({}), scene_dir_->path());
  }
  static void TearDownTestSuite() { scene_dir_.reset(); }

  // A private copy of the scene for a test that changes it.
  fs::path CopyScene() {
    fs::copy(scene_dir_->path(), dir_.path() / "work", fs::copy_options::recursive);
    return dir_.path() / "work";
  }

  static CommandResult Render(const fs::path& work, const fs::path& out,
                              const std::string& flags = "",
                              const std::string& meshes = "40_init") {
    return RunCommand(
        Quote(StageBinary("render").string()) + " --sfm " + Quote((work / "10_sfm").string()) +
        " --boundary " + Quote((work / "20_boundary").string()) + " --meshes " +
        Quote((work / meshes).string()) + " --out " + Quote(out.string()) + " " + flags);
  }

  // The run failed cleanly: the exit code, a message naming `names`, and
  // nothing written.
  void ExpectFailure(const CommandResult& r, int code, const std::string& names,
                     const fs::path& out) {
    EXPECT_EQ(r.exit_code, code) << r.output;
    EXPECT_NE(r.output.find(names), std::string::npos) << r.output;
    std::error_code ec;
    EXPECT_FALSE(fs::exists(out / "rectified.png", ec));
    EXPECT_FALSE(fs::exists(out / "rectified_grid.png", ec));
    EXPECT_FALSE(fs::exists(out / "render.json", ec));
  }

  static fs::path scene() { return scene_dir_->path(); }

  TempDir dir_;
  static std::unique_ptr<TempDir> scene_dir_;
};

std::unique_ptr<TempDir> RenderCli::scene_dir_;

TEST_F(RenderCli, WritesTheImagesAndAValidReport) {
  const fs::path out = dir_ / "60_render";
  const CommandResult r = Render(scene(), out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("render: wrote"), std::string::npos) << r.output;
  const cv::Mat image = cv::imread((out / "rectified.png").string());
  const cv::Mat grid = cv::imread((out / "rectified_grid.png").string());
  ASSERT_FALSE(image.empty());
  ASSERT_EQ(grid.size(), image.size());
  EXPECT_GT(cv::norm(image, grid, cv::NORM_L1), 0);
  const Json report = ReadJsonFile(out / "render.json");
  EXPECT_EQ(report["width"].get<int>(), image.cols);
  EXPECT_EQ(report["height"].get<int>(), image.rows);
  EXPECT_EQ(report["crop"]["rule"], "boundary-lines");
  EXPECT_EQ(report["size_rule"], "reference-density");
  EXPECT_TRUE(report["timing_s"].contains("read"));
  EXPECT_EQ(report["warnings"], Json::array()) << "a page M fits along every side";
  const CommandResult v = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                                     Quote((out / "render.json").string()));
  EXPECT_EQ(v.exit_code, 0) << v.output;
  // Nothing but the four outputs (no temporary files left behind).
  int files = 0;
  for (const auto& e : fs::directory_iterator(out)) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 4);
  // The label map: which photo coloured each pixel, the size of the page.
  const cv::Mat labels = cv::imread((out / "texture_labels.png").string());
  EXPECT_EQ(labels.size(), image.size());
  EXPECT_EQ(report["texture"]["method"], "fusion");
}

TEST_F(RenderCli, WidthFlagSetsTheOutputWidth) {
  const fs::path out = dir_ / "out";
  const CommandResult r = Render(scene(), out, "--width 150 --fill white --no-deskew");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat image = cv::imread((out / "rectified.png").string());
  EXPECT_EQ(image.cols, 150);
  const Json report = ReadJsonFile(out / "render.json");
  EXPECT_EQ(report["size_rule"], "width");
  EXPECT_EQ(report["fill_rgb"], Json::array({255, 255, 255}));
  // The record lists every option as the run had it.
  const Json& options = report["producer"]["options"];
  EXPECT_EQ(options["width"], 150);
  EXPECT_EQ(options["fill"], "white");
  EXPECT_EQ(options["deskew"], false);
  EXPECT_EQ(options["orient"], true);
  EXPECT_EQ(options["reach_real_sides"], true);
  EXPECT_EQ(options["reach_partial_below"], 0.6);
  EXPECT_EQ(options["page_format"], "none");
  EXPECT_EQ(options["deskew_by"], "lines");
  EXPECT_FALSE(options.contains("crop"));
}

// optimize's lines.json beside the meshes turns the page: its lines, 3
// degrees off the axes of M' while the sides are on them, set the deskew;
// --deskew-by sides (or too few lines) keeps the sides'. A broken
// lines.json is bad input.
TEST_F(RenderCli, DeskewFollowsTheLinesOfLinesJson) {
  const fs::path work = CopyScene();
  const MeshPair m = ReadMeshPair(work / "40_init");
  Eigen::Vector2d lo = m.mesh2d[0], hi = lo;
  for (const auto& q : m.mesh2d) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const double a = 3 * M_PI / 180;
  const Eigen::Vector2d along(std::cos(a), std::sin(a)), normal(-std::sin(a), std::cos(a));
  auto write_lines = [&](int n) {
    Json lines = Json::array();
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2d start = lo + Eigen::Vector2d(0.1, 0.1 + 0.08 * k).cwiseProduct(hi - lo);
      Json flat = Json::array();
      for (int j = 0; j <= 10; ++j) {
        const Eigen::Vector2d p = start + along * (0.05 * j * (hi - lo).x());
        flat.push_back({p.x(), p.y()});
      }
      lines.push_back({{"kind", "text"}, {"normal", {normal.x(), normal.y()}}, {"flat", flat}});
    }
    WriteJsonAtomic(work / "40_init/lines.json", {{"format", "docunfold.lines"}, {"lines", lines}});
  };
  auto rotation = [&](const std::string& flags, const std::string& name) {
    const CommandResult r = Render(work, dir_ / name, flags);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const Json report = ReadJsonFile(dir_ / name / "render.json");
    return std::make_pair(report["rotation_deg"].get<double>(),
                          report["deskew_source"].get<std::string>());
  };
  const auto [sides_deg, sides_source] = rotation("", "none");
  EXPECT_EQ(sides_source, "sides");
  write_lines(10);
  const auto [lines_deg, lines_source] = rotation("", "lines");
  EXPECT_EQ(lines_source, "lines");
  EXPECT_NEAR(lines_deg, -3, 0.05);
  EXPECT_GT(std::abs(lines_deg - sides_deg), 2);
  EXPECT_EQ(rotation("--deskew-by sides", "forced").first, sides_deg);
  write_lines(3);
  EXPECT_EQ(rotation("", "few").second, "sides");
  // Print too small for Tesseract (the page 100 px wide): the reader's down
  // from lines.json decides the quarter turn (down along +x in the output
  // takes one clockwise turn, along -x three); without it the page stays.
  ASSERT_EQ(Render(work, dir_ / "small", "--width 100").exit_code, 0);
  const Json quiet = ReadJsonFile(dir_ / "small" / "render.json")["orientation"];
  ASSERT_FALSE(quiet["decided"].get<bool>()) << quiet.dump();
  EXPECT_EQ(quiet["quarter_turns_clockwise"], 0);
  for (const auto& [down, turns] : std::vector<std::pair<double, int>>{{1, 1}, {-1, 3}}) {
    Json doc = ReadJsonFile(work / "40_init/lines.json");
    doc["text_down_flat"] = {down, 0.0};
    WriteJsonAtomic(work / "40_init/lines.json", doc);
    const std::string name = "down" + std::to_string(turns);
    ASSERT_EQ(Render(work, dir_ / name, "--width 100").exit_code, 0);
    const Json o = ReadJsonFile(dir_ / name / "render.json")["orientation"];
    EXPECT_EQ(o["quarter_turns_clockwise"], turns) << o.dump();
    EXPECT_EQ(o["by"], "baselines") << o.dump();
  }
  // Text lines running down the page in M' and no down known: a quarter
  // turn makes them run across it (a receipt from another detector's file
  // was left sideways before).
  {
    Json doc = ReadJsonFile(work / "40_init/lines.json");
    doc.erase("text_down_flat");
    for (Json& line : doc["lines"]) {
      for (Json& p : line["flat"]) p = {p[1].get<double>(), p[0].get<double>()};
      line["normal"] = {line["normal"][1].get<double>(), line["normal"][0].get<double>()};
    }
    WriteJsonAtomic(work / "40_init/lines.json", doc);
    ASSERT_EQ(Render(work, dir_ / "sideways", "--width 100").exit_code, 0);
    const Json o = ReadJsonFile(dir_ / "sideways" / "render.json")["orientation"];
    ASSERT_FALSE(o["decided"].get<bool>()) << o.dump();
    EXPECT_EQ(o["quarter_turns_clockwise"].get<int>() % 2, 1) << o.dump();
    EXPECT_NE(o.value("note", "").find("ran down the page"), std::string::npos) << o.dump();
    EXPECT_EQ(o["by"], "text lines") << o.dump();
  }
  // Without lines.json (init-mesh's meshes), features.json's down in the
  // reference image, carried into M' through the text segments, does it.
  fs::remove(work / "40_init/lines.json");
  for (const auto& [down, turns] : std::vector<std::pair<double, int>>{{1, 1}, {-1, 3}}) {
    Json segments = Json::array();
    for (int y = 200; y <= 300; y += 10)
      segments.push_back({{"kind", "text"}, {"points", {{260, y}, {320, y}, {380, y}}}});
    const fs::path features = work / ("features" + std::to_string(turns) + ".json");
    WriteJsonAtomic(features, {{"format", "docunfold.features"},
                               {"version", 1},
                               {"segments", segments},
                               {"text_down", {down, 0.0}}});
    const std::string name = "features" + std::to_string(turns);
    ASSERT_EQ(
        Render(work, dir_ / name, "--width 100 --features " + Quote(features.string())).exit_code,
        0);
    const Json o = ReadJsonFile(dir_ / name / "render.json")["orientation"];
    EXPECT_EQ(o["quarter_turns_clockwise"], turns) << o.dump();
    EXPECT_NE(o.value("note", "").find("features.json"), std::string::npos) << o.dump();
  }
  ExpectFailure(
      Render(work, dir_ / "nofeatures", "--features " + Quote((work / "none.json").string())), 3,
      "none.json", dir_ / "nofeatures");
  WriteTextAtomic(work / "40_init/lines.json", "{\"lines\": [{\"normal\": [0, 1]}]}");
  ExpectFailure(Render(work, dir_ / "broken"), 3, "lines.json:/lines/0", dir_ / "broken");
  WriteTextAtomic(work / "40_init/lines.json",
                  "{\"lines\": [{\"normal\": [0, 1], \"flat\": [[0, \"a\"]]}]}");
  ExpectFailure(Render(work, dir_ / "typed"), 3, "lines.json:/lines/0/flat", dir_ / "typed");
}

TEST_F(RenderCli, ContradictoryFlagsAreUsageErrors) {
  const fs::path out = dir_ / "out";
  ExpectFailure(Render(scene(), out, "--width 100 --dpi 300"), 2, "excludes", out);
  ExpectFailure(Render(scene(), out, "--dpi 300"), 2, "--page-width-mm", out);
  ExpectFailure(Render(scene(), out, "--fill purple"), 2, "--fill", out);
  ExpectFailure(Render(scene(), out, "--width 100000"), 2, "--max-pixels", out);
  ExpectFailure(Render(scene(), out, "--shading dim"), 2, "--shading", out);
  ExpectFailure(Render(scene(), out, "--page-format a3"), 2, "--page-format", out);
  ExpectFailure(Render(scene(), out, "--page-format 0.7"), 2, "--page-format", out);
  // Switches tried and not kept are gone.
  ExpectFailure(Render(scene(), out, "--crop middle"), 2, "--crop", out);
  ExpectFailure(Render(scene(), out, "--better-views 2"), 2, "--better-views", out);
  ExpectFailure(Render(scene(), out, "--scattered-sides box"), 2, "--scattered-sides", out);
}

// --shading remove divides the light out (common/shading.h, tested there):
// the report says so, the page's pixels change and the size does not.
TEST_F(RenderCli, ShadingRemoveIsReportedAndKeepsTheSize) {
  const fs::path keep = dir_ / "keep", removed = dir_ / "removed";
  ASSERT_EQ(Render(scene(), keep).exit_code, 0);
  const CommandResult r = Render(scene(), removed, "--shading remove");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json kept_report = ReadJsonFile(keep / "render.json");
  const Json report = ReadJsonFile(removed / "render.json");
  EXPECT_FALSE(kept_report["shading"]["removed"].get<bool>());
  EXPECT_TRUE(report["shading"]["removed"].get<bool>());
  EXPECT_GT(report["shading"]["paper_fraction"].get<double>(), 0.5);
  EXPECT_EQ(report["producer"]["options"]["shading"], "remove");
  const cv::Mat a = cv::imread((keep / "rectified.png").string());
  const cv::Mat b = cv::imread((removed / "rectified.png").string());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GT(cv::norm(a, b, cv::NORM_L1), 0);
}

TEST_F(RenderCli, MissingMeshesAreBadInput) {
  const fs::path out = dir_ / "out";
  ExpectFailure(Render(scene(), out, "", "50_optimize"), 3, "50_optimize", out);
  const fs::path work = CopyScene();
  fs::remove(work / "40_init" / "mesh2d.ply");
  ExpectFailure(Render(work, out), 3, "mesh2d.ply", out);
}

TEST_F(RenderCli, MeshesOfDifferentGridsAreBadInput) {
  const fs::path work = CopyScene();
  PlyData m2 = ReadPly(work / "40_init" / "mesh2d.ply");
  // Drop the last row: a 43x56 grid beside mesh3d's 43x57.
  const auto grid = m2.GridSize();
  ASSERT_TRUE(grid);
  const int nx = (*grid)[0], ny = (*grid)[1] - 1;
  m2.vertices.resize(size_t(nx) * ny);
  QuadGrid g{nx, ny};
  m2.faces = g.Faces();
  m2.comments.clear();
  m2.SetGridSize(nx, ny);
  WritePly(work / "40_init" / "mesh2d.ply", m2);
  const fs::path out = dir_ / "out";
  ExpectFailure(Render(work, out), 3, "differs from mesh3d.ply", out);
}

TEST_F(RenderCli, MeshBehindTheCameraIsBadInput) {
  const fs::path work = CopyScene();
  MeshPair m = ReadMeshPair(work / "40_init");
  for (auto& v : m.mesh3d) v.z() = -v.z();
  WriteMeshPair(work / "40_init", m);
  const fs::path out = dir_ / "out";
  ExpectFailure(Render(work, out), 3, "behind the reference camera", out);
}

TEST_F(RenderCli, BoundaryOfAnotherImageIsBadInput) {
  const fs::path work = CopyScene();
  Json b = ReadJsonFile(work / "20_boundary" / "boundary.json");
  b["width"] = 1600;
  b["height"] = 1200;
  WriteJsonAtomic(work / "20_boundary" / "boundary.json", b);
  const fs::path out = dir_ / "out";
  ExpectFailure(Render(work, out), 3, "boundary.json: made for a 1600x1200 image", out);
  fs::remove(work / "20_boundary" / "boundary.json");
  ExpectFailure(Render(work, out), 3, "boundary.json", out);
}

TEST_F(RenderCli, BrokenSfmOutputIsBadInput) {
  const fs::path work = CopyScene();
  const fs::path out = dir_ / "out";
  std::ofstream(work / "10_sfm" / "reference.png", std::ios::trunc).close();
  ExpectFailure(Render(work, out), 3, "reference.png", out);
  fs::remove(work / "10_sfm" / "cameras.json");
  ExpectFailure(Render(work, out), 3, "cameras.json", out);
}

TEST_F(RenderCli, UnwritableOutputExits4WithoutPartialFiles) {
  // --out below a regular file.
  std::ofstream(dir_ / "file").close();
  const CommandResult r = Render(scene(), dir_ / "file" / "out");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  // One target that cannot be replaced: none of the three is written.
  const fs::path out = dir_ / "out";
  fs::create_directories(out / "rectified_grid.png");
  const CommandResult r2 = Render(scene(), out);
  EXPECT_EQ(r2.exit_code, 4) << r2.output;
  EXPECT_FALSE(fs::exists(out / "rectified.png"));
  EXPECT_FALSE(fs::exists(out / "render.json"));
  int files = 0;
  for (const auto& e : fs::directory_iterator(out)) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 1);  // only the directory that was in the way
}

}  // namespace
}  // namespace docunfold::testing
