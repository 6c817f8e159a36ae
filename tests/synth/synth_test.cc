// synth: deterministic, self-consistent data sets in the ground-truth layout
// (images/, ground_truth/), and clear failures on bad requests.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "common/json_io.h"
#include "stages/synth/folds.h"
#include "tests/support/ground_truth.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

std::string Synth(const std::string& args) {
  return Quote(StageBinary("synth").string()) + " " + args;
}

const char* kSmall = "--views 2 --width 480 --height 360 --creases 2";

TEST(Synth, SameSeedGivesIdenticalFilesAndAnotherSeedDoesNot) {
  TempDir dir;
  for (const char* name : {"a", "b"})
    ASSERT_EQ(
        RunCommand(Synth(std::string(kSmall) + " --seed 7 --out " + Quote((dir / name).string())))
            .exit_code,
        0);
  ASSERT_EQ(
      RunCommand(Synth(std::string(kSmall) + " --seed 8 --out " + Quote((dir / "c").string())))
          .exit_code,
      0);
  for (const char* f : {"images/view_00.jpg", "images/view_01.jpg", "ground_truth/flat.png",
                        "ground_truth/mesh.ply", "ground_truth/cameras.json",
                        "ground_truth/features.json", "ground_truth/text.txt"}) {
    EXPECT_EQ(ReadFileText(dir / "a" / f), ReadFileText(dir / "b" / f)) << f;
  }
  EXPECT_NE(ReadFileText(dir / "a/images/view_00.jpg"), ReadFileText(dir / "c/images/view_00.jpg"));
  EXPECT_NE(ReadFileText(dir / "a/COMMAND").find("--seed 7"), std::string::npos);
}

TEST(Synth, WritesTheGroundTruthLayoutAndItValidates) {
  TempDir dir;
  for (const char* kind : {"text", "table", "receipt", "poster"}) {
    const fs::path out = dir / kind;
    CommandResult r = RunCommand(
        Synth(std::string(kSmall) + " --kind " + kind + " --out " + Quote(out.string())));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (const char* f : {"flat.png", "text.txt", "page.json", "mesh.ply", "cameras.json",
                          "features.json", "synth.json"})
      EXPECT_TRUE(fs::is_regular_file(out / "ground_truth" / f)) << kind << " " << f;
    CommandResult v = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                                 Quote((out / "ground_truth/cameras.json").string()) + " " +
                                 Quote((out / "ground_truth/features.json").string()) + " " +
                                 Quote((out / "ground_truth/page.json").string()) + " " +
                                 Quote((out / "ground_truth/synth.json").string()));
    EXPECT_EQ(v.exit_code, 0) << v.output;
    auto gt = LoadGroundTruth(out);
    ASSERT_TRUE(gt);
    EXPECT_EQ(gt->cameras.views.size(), 2u);
    EXPECT_TRUE(gt->mesh.GridSize().has_value());
    // Text lines, rules where the kind has them, and the four page edges.
    int text = 0, rule = 0, border = 0;
    for (const TrueLine& l : gt->lines) {
      text += l.kind == "text";
      rule += l.kind == "rule";
      border += l.kind == "border";
    }
    EXPECT_GT(text, 5) << kind;
    EXPECT_EQ(border, 4) << kind;
    if (std::string(kind) == "table" || std::string(kind) == "poster") {
      EXPECT_GT(rule, 4);
    }
    EXPECT_GT(fs::file_size(out / "ground_truth/text.txt"), 100u) << kind;
    // Readers of synth.json (evaluate's LineRecallRequired, the tests) take
    // the page kind, curl and cut-off from its producer record.
    const Json options = ReadJsonFile(out / "ground_truth/synth.json")["producer"]["options"];
    EXPECT_EQ(options.value("kind", ""), kind);
    EXPECT_EQ(options.value("curl", true), false);
    EXPECT_EQ(options.value("cut_off", true), false);
    EXPECT_EQ(options.value("creases", 0), 2);
  }
}

TEST(Synth, FoldedSheetIsAnIsometryOfThePage) {
  std::mt19937 rng(3);
  synth::FoldOptions options;
  options.creases = 3;
  options.curl = true;
  auto folds = synth::RandomFolds(0.21, 0.297, options, &rng);
  ASSERT_EQ(folds.size(), 4u);
  synth::FoldedSheet sheet(0.21, 0.297, folds);
  // Short steps along random directions keep their length on the surface
  // (a chord of an arc is shorter by at most ~(step/r)^2/24).
  std::uniform_real_distribution<double> u(0.01, 0.2), v(0.01, 0.287), a(0, 6.283);
  double worst = 0;
  bool bent = false;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector2d p(u(rng), v(rng));
    const double angle = a(rng);
    const Eigen::Vector2d q = p + 2e-4 * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    const double d = (sheet.Map(p) - sheet.Map(q)).norm();
    worst = std::max(worst, std::abs(d - 2e-4) / 2e-4);
    bent = bent || std::abs(sheet.Map(p).z()) > 1e-3;
  }
  EXPECT_LT(worst, 0.01);
  EXPECT_TRUE(bent);
}

TEST(Synth, CutOffFramingLeavesPartOfThePageOutsideEveryView) {
  TempDir dir;
  CommandResult r =
      RunCommand(Synth(std::string(kSmall) + " --cut-off --out " + Quote((dir / "cut").string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(ReadJsonFile(dir / "cut/ground_truth/synth.json")["producer"]["options"].value(
      "cut_off", false));
  auto gt = LoadGroundTruth(dir / "cut");
  ASSERT_TRUE(gt);
  for (const PinholeCamera& cam : gt->cameras.views) {
    int inside = 0;
    for (const Eigen::Vector3d& v : gt->mesh.vertices) {
      const Eigen::Vector2d p = cam.Project(v);
      inside += p.x() >= 0 && p.y() >= 0 && p.x() < cam.width && p.y() < cam.height;
    }
    const double fraction = double(inside) / gt->mesh.vertices.size();
    EXPECT_GT(fraction, 0.5) << cam.image;
    EXPECT_LT(fraction, 0.97) << cam.image;
  }
}

TEST(Synth, LengthsInMillimetres) {
  // A widest crease below the narrowest counts as the narrowest: every
  // crease is then 6 mm wide.
  TempDir dir;
  CommandResult r = RunCommand(Synth(std::string(kSmall) +
                                     " --crease-width-mm 6 --crease-width-max-mm 2 --page-size " +
                                     "150x200 --out " + Quote((dir / "mm").string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json synth = ReadJsonFile(dir / "mm/ground_truth/synth.json");
  ASSERT_EQ(synth["folds"].size(), 2u);
  for (const Json& f : synth["folds"]) EXPECT_NEAR(f["width_mm"].get<double>(), 6.0, 1e-9);
  EXPECT_EQ(synth["producer"]["options"]["crease_width_mm"], "6");
  EXPECT_EQ(synth["producer"]["options"]["page_size"], "150x200");
  const Json page = ReadJsonFile(dir / "mm/ground_truth/page.json");
  EXPECT_DOUBLE_EQ(page["width_m"].get<double>(), 0.15);
  EXPECT_DOUBLE_EQ(page["height_m"].get<double>(), 0.2);
}

TEST(Synth, BadRequestsFailWithUsageErrorsAndLeaveNothing) {
  TempDir dir;
  CommandResult r = RunCommand(Synth("--kind leaflet --out " + Quote((dir / "x").string())));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--kind: expected text|table|receipt|poster, got 'leaflet'"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "x"));

  r = RunCommand(Synth("--background lava --out " + Quote((dir / "x").string())));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(fs::exists(dir / "x"));

  fs::create_directories(dir / "taken");
  std::ofstream(dir / "taken/keep.txt") << "mine";
  r = RunCommand(Synth(std::string(kSmall) + " --out " + Quote((dir / "taken").string())));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("exists (pass --force"), std::string::npos) << r.output;
  EXPECT_EQ(ReadFileText(dir / "taken/keep.txt"), "mine");

  r = RunCommand(Synth("--page-size 21 --out " + Quote((dir / "x").string())));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--page-size"), std::string::npos) << r.output;
  // No temporary folders are left beside the output.
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
}

}  // namespace
}  // namespace docunfold::testing
