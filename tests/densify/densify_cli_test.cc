// densify's command line: a good run on set01 (true cameras and outline)
// and every kind of bad input, each a one-line error with its exit code.
#include <gtest/gtest.h>

#include <fstream>
#include <optional>
#include <sstream>

#include "tests/init-mesh/work_fixture.h"
#include "tests/isometry/test_meshes.h"
#include "tests/support/test_support.h"
#include "tests/support/truth_frame.h"

namespace docunfold::testing {
namespace {

std::string Slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

class DensifyCli : public ::testing::Test {
 protected:
  void SetUp() override {
    set_ = SampleDir("set01");
    gt_ = LoadGroundTruth(set_);
    if (!gt_) GTEST_SKIP() << "samples/set01 has no ground truth";
    WriteWork();
  }
  void WriteWork() const {
    SfmFromTruthOptions o;
    o.num_points = 800;
    WriteWorkFromTruth(*gt_, ChooseReferenceView(*gt_), dir_.path(), o);
  }
  CommandResult Run(const std::string& extra, const fs::path& data = {}) const {
    return RunCommand(Quote(StageBinary("densify").string()) + " --data " +
                      Quote((data.empty() ? set_ : data).string()) + " --sfm " +
                      Quote((dir_ / "10_sfm").string()) + " --boundary " +
                      Quote((dir_ / "20_boundary").string()) + " " + extra + " 2>&1");
  }
  std::string Out() const { return "--out " + Quote((dir_ / "25_points").string()); }
  fs::path set_;
  std::optional<GroundTruth> gt_;
  TempDir dir_;
};

TEST_F(DensifyCli, WritesItsFilesAndKeepsSfmPointsFirstAndUnchanged) {
  const std::string before = Slurp(dir_ / "10_sfm/points.ply");
  const CommandResult r = Run(Out());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("texture points"), std::string::npos) << r.output;
  EXPECT_EQ(Slurp(dir_ / "10_sfm/points.ply"), before);  // input untouched
  const PlyData sfm = ReadPly(dir_ / "10_sfm/points.ply");
  const PlyData all = ReadPly(dir_ / "25_points/points.ply");
  ASSERT_GT(all.vertices.size(), sfm.vertices.size());
  for (size_t i = 0; i < sfm.vertices.size(); ++i)
    ASSERT_LT((all.vertices[i] - sfm.vertices[i]).norm(), 1e-6) << i;
  for (const char* p : {"track_length", "reprojection_error", "source"})
    EXPECT_NE(all.FindProperty(p), nullptr) << p;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "25_points/overlay.png"));
  const CommandResult v = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                                     Quote((dir_ / "25_points/points.json").string()));
  EXPECT_EQ(v.exit_code, 0) << v.output;
  const Json report = ReadJsonFile(dir_ / "25_points/points.json");
  EXPECT_TRUE(report["points"].contains("steps")) << report.dump();
  EXPECT_TRUE(report.contains("steps")) << report.dump();
  for (const auto& e : fs::directory_iterator(dir_ / "25_points"))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST_F(DensifyCli, SurfacePrewarpIsASecondPassCountedApart) {
  const CommandResult plain = Run(Out() + " --no-surface-prewarp");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const Json before = ReadJsonFile(dir_ / "25_points/points.json");
  EXPECT_EQ(before["points"]["texture_surface_prewarp"].get<int>(), 0);
  EXPECT_FALSE(before["producer"]["options"]["surface_prewarp"].get<bool>());
  const CommandResult r = Run(Out());  // on by default
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("through the points' surface"), std::string::npos) << r.output;
  const Json after = ReadJsonFile(dir_ / "25_points/points.json");
  // The first pass is the same; the second only adds.
  EXPECT_EQ(
      after["points"]["texture"].get<int>() - after["points"]["texture_surface_prewarp"].get<int>(),
      before["points"]["texture"].get<int>());
  EXPECT_TRUE(after["producer"]["options"]["surface_prewarp"].get<bool>());
  const CommandResult v = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                                     Quote((dir_ / "25_points/points.json").string()));
  EXPECT_EQ(v.exit_code, 0) << v.output;
}

TEST_F(DensifyCli, HelpAndUsage) {
  const CommandResult help = RunCommand(Quote(StageBinary("densify").string()) + " --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("--no-outline"), std::string::npos) << help.output;
  const CommandResult none = RunCommand(Quote(StageBinary("densify").string()) + " 2>&1");
  EXPECT_EQ(none.exit_code, 2) << none.output;
  const CommandResult bad = Run(Out() + " --max-image-size 10");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
}

TEST_F(DensifyCli, MissingPhotoNamesIt) {
  TempDir empty;
  fs::create_directories(empty / "images");
  const CommandResult r = Run(Out(), empty.path());
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find((empty / "images").string()), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "25_points/points.ply"));
}

TEST_F(DensifyCli, BadInputFilesAreNamed) {
  {
    std::ofstream(dir_ / "10_sfm/points.ply", std::ios::trunc);  // empty file
    const CommandResult r = Run(Out());
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find("points.ply"), std::string::npos) << r.output;
  }
  WriteWork();
  fs::remove(dir_ / "20_boundary/mask.png");
  const CommandResult r = Run(Out());
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("mask.png"), std::string::npos) << r.output;
}

TEST_F(DensifyCli, UnwritableOutputIsExitFour) {
  std::ofstream(dir_ / "not_a_dir") << "x";
  const CommandResult r = Run("--out " + Quote((dir_ / "not_a_dir").string()));
  EXPECT_EQ(r.exit_code, 4) << r.output;
}

}  // namespace
}  // namespace docunfold::testing
