// synth's hard cases: a receipt as a till prints it (--roll), a panel
// standing past upright (--steep-fold), a flap folded back over the page
// (--flap) and a curled end (--end-curl). Each writes a true surface that is
// isometric to the page and does not pass through itself, shaped as asked.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <sstream>

#include "common/json_io.h"
#include "common/ply.h"
#include "stages/synth/folds.h"
#include "stages/synth/scene.h"
#include "tests/support/ground_truth.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

constexpr double kPi = 3.14159265358979323846;
const char* kTiny = "--views 1 --width 320 --height 240";

// Runs synth with `args` into dir/name and loads its ground truth.
std::optional<GroundTruth> Make(const TempDir& dir, const std::string& name,
                                const std::string& args) {
  const fs::path out = dir / name;
  CommandResult r = RunCommand(Quote(StageBinary("synth").string()) + " " + kTiny + " " + args +
                               " --out " + Quote(out.string()));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  if (r.exit_code != 0) return std::nullopt;
  return LoadGroundTruth(out);
}

// The true surface's grid: vertices, their s, t and the printed side's
// normal of every quad (d/dv x d/du, as synth shades it).
struct Grid {
  int nx = 0, ny = 0;
  const GroundTruth* gt = nullptr;
  std::vector<double> s, t;
  const Eigen::Vector3d& At(int r, int c) const { return gt->mesh.vertices[r * nx + c]; }
  Eigen::Vector3d Normal(int r, int c) const {
    return (At(r + 1, c) - At(r, c)).cross(At(r, c + 1) - At(r, c)).normalized();
  }
  // The panel holding the page centre.
  Eigen::Vector3d RootNormal() const { return Normal(ny / 2, nx / 2); }
};

Grid GridOf(const GroundTruth& gt) {
  Grid g;
  g.gt = &gt;
  const auto size = gt.mesh.GridSize();
  EXPECT_TRUE(size.has_value());
  if (!size) return g;
  g.nx = (*size)[0];
  g.ny = (*size)[1];
  g.s = gt.mesh.FindProperty("s")->values;
  g.t = gt.mesh.FindProperty("t")->values;
  return g;
}

// Every grid edge of mesh.ply against its length on the flat page: as long
// on the flat panels, a chord (never longer) across a bend.
void ExpectIsometric(const Grid& g) {
  int exact = 0, edges = 0;
  double worst_ratio = 1;
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c)
      for (const auto& [dr, dc] : {std::pair{0, 1}, std::pair{1, 0}}) {
        if (r + dr >= g.ny || c + dc >= g.nx) continue;
        const int i = r * g.nx + c, j = (r + dr) * g.nx + c + dc;
        const double page =
            std::hypot((g.s[j] - g.s[i]) * g.gt->width_m, (g.t[j] - g.t[i]) * g.gt->height_m);
        const double chord = (g.gt->mesh.vertices[j] - g.gt->mesh.vertices[i]).norm();
        EXPECT_LT(chord, page * (1 + 1e-4) + 1e-7);
        worst_ratio = std::min(worst_ratio, chord / page);
        exact += std::abs(chord / page - 1) < 1e-3;
        ++edges;
      }
  EXPECT_GT(double(exact) / edges, 0.9);
  EXPECT_GT(worst_ratio, 0.75);  // a 2 mm chord of a 1 mm radius keeps 0.82
}

// The folded sheet synth.json records, checked finely: short steps keep
// their length, and the sheet does not pass through itself.
void ExpectValidSheet(const fs::path& dataset) {
  const Json synth = ReadJsonFile(dataset / "ground_truth/synth.json");
  const Json page = ReadJsonFile(dataset / "ground_truth/page.json");
  std::vector<synth::Fold> folds;
  for (const Json& f : synth["folds"]) {
    synth::Fold fold;
    fold.point = {f["point_m"][0].get<double>(), f["point_m"][1].get<double>()};
    fold.direction = {f["direction"][0].get<double>(), f["direction"][1].get<double>()};
    fold.width = f["width_mm"].get<double>() / 1000;
    fold.angle = f["angle_deg"].get<double>() * kPi / 180;
    folds.push_back(fold);
  }
  const double W = page["width_m"].get<double>(), H = page["height_m"].get<double>();
  synth::FoldedSheet sheet(W, H, folds);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, W), v(0, H), a(0, 2 * kPi);
  double worst = 0;
  for (int i = 0; i < 5000; ++i) {
    const Eigen::Vector2d p(u(rng), v(rng));
    const double angle = a(rng);
    const Eigen::Vector2d q = p + 2e-4 * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    worst = std::max(worst, std::abs((sheet.Map(p) - sheet.Map(q)).norm() - 2e-4) / 2e-4);
  }
  EXPECT_LT(worst, 0.01);
  EXPECT_FALSE(synth::SelfIntersects(sheet, 0.001));
}

// Degrees between the printed side's normal at quad (r, c) and the root's.
double TurnDeg(const Grid& g, int r, int c) {
  return std::acos(std::clamp(g.Normal(r, c).dot(g.RootNormal()), -1.0, 1.0)) * 180 / kPi;
}

TEST(SynthShapes, RollReceiptPrintsTillRowsAndRecordsTheirBaselines) {
  TempDir dir;
  for (const char* roll : {"58", "80"}) {
    auto gt = Make(dir, roll, std::string("--creases 0 --kind receipt --seed 3 --roll ") + roll);
    ASSERT_TRUE(gt);
    EXPECT_NEAR(gt->width_m, std::stoi(roll) / 1000.0, 1e-9);
    EXPECT_GE(gt->height_m, 0.14);
    EXPECT_LE(gt->height_m, 0.24);
    const int columns = std::string(roll) == "58" ? 32 : 48;
    std::istringstream text(ReadFileText(dir / roll / "ground_truth/text.txt"));
    std::string line;
    int rows = 0, priced = 0, separators = 0, total = 0;
    const std::regex item(R"(^\S.*\S {2,}-?\d+\.\d\d( [AB])?$)");
    while (std::getline(text, line)) {
      ++rows;
      EXPECT_LE(int(line.size()), columns) << line;
      priced += std::regex_match(line, item);
      separators +=
          line.size() == size_t(columns) && line.find_first_not_of(line[0]) == std::string::npos;
      total += line.rfind("TOTAL", 0) == 0;
    }
    EXPECT_GE(priced, 6) << roll;
    EXPECT_EQ(separators, 3) << roll;
    EXPECT_EQ(total, 1) << roll;
    // One baseline in features.json for every printed row but the
    // separators, which have no ink on theirs: one rule line for each bar
    // of their dashes, dots or double lines, across the printable width.
    // The priced rows end together at the printable width's right edge.
    std::vector<double> ends;
    int baselines = 0, bars = 0;
    for (const TrueLine& l : gt->lines) {
      const double u0 = l.points.front().x() / gt->flat_width * gt->width_m;
      const double u1 = l.points.back().x() / gt->flat_width * gt->width_m;
      if (l.kind == "text") {
        ++baselines;
        ends.push_back(u1);
      } else if (l.kind == "rule") {
        ++bars;
        EXPECT_GT(u1 - u0, 0.95 * (std::string(roll) == "58" ? 0.048 : 0.072)) << roll;
      }
    }
    EXPECT_EQ(baselines, rows - separators) << roll;
    EXPECT_GE(bars, separators) << roll;
    EXPECT_LE(bars, 2 * separators) << roll;
    const double printable = std::string(roll) == "58" ? 0.048 : 0.072;
    const double right = (gt->width_m + printable) / 2;
    int at_right = 0;
    for (double e : ends) at_right += std::abs(e - right) < 0.0015;
    EXPECT_GE(at_right, priced) << roll;
  }
}

TEST(SynthShapes, SteepFoldStandsPastUpright) {
  TempDir dir;
  auto gt = Make(dir, "steep", "--creases 0 --kind receipt --roll 58 --steep-fold 130 --seed 4");
  ASSERT_TRUE(gt);
  const Grid g = GridOf(*gt);
  ExpectIsometric(g);
  ExpectValidSheet(dir / "steep");
  // The end panel turns by 130 degrees from the root: past upright.
  double most = 0;
  int past_upright = 0;
  for (int r = 0; r + 1 < g.ny; ++r)
    for (int c = 0; c + 1 < g.nx; ++c) {
      const double turn = TurnDeg(g, r, c);
      most = std::max(most, turn);
      past_upright += turn > 100;
    }
  EXPECT_NEAR(most, 130, 1.5);
  EXPECT_GT(past_upright, (g.nx - 1) * (g.ny - 1) / 8);
  // The root lies flat on the table, print up.
  EXPECT_GT(g.RootNormal().z(), 0.999);
}

TEST(SynthShapes, FlapLiesOverThePageBackUpAndRendersAsBlankPaper) {
  TempDir dir;
  for (const char* flap : {"corner", "end"}) {
    auto gt =
        Make(dir, flap,
             std::string(
                 "--creases 0 --kind text --page-size 120x160 --flap-angle 178 --seed 6 --flap ") +
                 flap);
    ASSERT_TRUE(gt);
    const Grid g = GridOf(*gt);
    ExpectIsometric(g);
    ExpectValidSheet(dir / flap);
    const double root_z = g.At(g.ny / 2, g.nx / 2).z();
    std::vector<Eigen::Vector3d> flap_points, root_points;
    for (int r = 0; r + 1 < g.ny; ++r)
      for (int c = 0; c + 1 < g.nx; ++c) {
        const double turn = TurnDeg(g, r, c);
        const Eigen::Vector3d centre = (g.At(r, c) + g.At(r + 1, c + 1)) / 2;
        if (turn > 177) {
          flap_points.push_back(centre);
          EXPECT_GT(centre.z(), root_z + 0.0005);  // above the page, not through it
        } else if (turn < 1) {
          root_points.push_back(centre);
        }
      }
    EXPECT_GT(flap_points.size(), size_t((g.nx - 1) * (g.ny - 1) / 30)) << flap;

    // Rendered with print everywhere but the paper-coloured corner synth
    // takes the back's colour from, the flap shows blank paper and the page
    // shows print.
    synth::PageSurface surface;
    surface.nx = g.nx;
    surface.ny = g.ny;
    surface.vertices = gt->mesh.vertices;
    for (size_t i = 0; i < g.s.size(); ++i) surface.st.emplace_back(g.s[i], g.t[i]);
    surface.triangles = gt->triangles;
    cv::Mat texture(320, 240, CV_8UC3, cv::Scalar(30, 30, 30));
    texture(cv::Rect(0, 0, 8, 8)).setTo(cv::Scalar(240, 240, 240));
    std::mt19937 rng(1);
    const synth::Table table = synth::MakeTable(synth::Background::kPlain, &rng);
    synth::Lighting light;
    light.direction = Eigen::Vector3d::UnitZ();
    light.ambient = light.diffuse = 0.5;
    const PinholeCamera& cam = gt->cameras.views[0];
    const cv::Mat image = synth::RenderView(surface, texture, table, light, cam);
    auto grey = [&](const Eigen::Vector3d& x) {
      const Eigen::Vector2d p = cam.Project(x);
      const cv::Vec3b v = image.at<cv::Vec3b>(int(std::lround(p.y())), int(std::lround(p.x())));
      return (v[0] + v[1] + v[2]) / 3.0;
    };
    int blank = 0, printed = 0;
    for (const Eigen::Vector3d& x : flap_points) blank += grey(x) > 150;
    for (const Eigen::Vector3d& x : root_points) printed += grey(x) < 60;
    EXPECT_GT(blank, int(flap_points.size() * 0.95)) << flap;
    EXPECT_GT(printed, int(root_points.size() / 3)) << flap;
  }
}

TEST(SynthShapes, EndCurlTurnsMostNearTheEdge) {
  TempDir dir;
  auto gt = Make(dir, "curl",
                 "--creases 0 --kind receipt --roll 80 --end-curl top --end-curl-length-mm 36 "
                 "--end-curl-angle 150 --seed 8");
  ASSERT_TRUE(gt);
  const Grid g = GridOf(*gt);
  ExpectIsometric(g);
  ExpectValidSheet(dir / "curl");
  // Turn of the row of quads at `mm` from the top edge.
  auto turn_at = [&](double mm) {
    const int r = std::clamp(int(mm / 1000 / gt->height_m * (g.ny - 1)), 0, g.ny - 2);
    return TurnDeg(g, r, g.nx / 2);
  };
  EXPECT_NEAR(turn_at(0), 150, 8);
  EXPECT_LT(turn_at(40), 1);
  // Curvature grows towards the edge: the outer half turns further.
  EXPECT_LT(turn_at(18) - turn_at(36), turn_at(0) - turn_at(18));
  // The bottom end and the root lie flat.
  EXPECT_LT(turn_at(gt->height_m * 1000 - 1), 1);
}

TEST(SynthShapes, SameSeedGivesIdenticalFilesAndBadCombinationsFail) {
  TempDir dir;
  const std::string args = "--kind receipt --roll 80 --flap corner --end-curl bottom --creases 1";
  for (const char* name : {"a", "b"}) ASSERT_TRUE(Make(dir, name, args + " --seed 11"));
  ASSERT_TRUE(Make(dir, "c", args + " --seed 12"));
  for (const char* f : {"images/view_00.jpg", "ground_truth/flat.png", "ground_truth/mesh.ply",
                        "ground_truth/features.json", "ground_truth/text.txt"})
    EXPECT_EQ(ReadFileText(dir / "a" / f), ReadFileText(dir / "b" / f)) << f;
  EXPECT_NE(ReadFileText(dir / "a/images/view_00.jpg"), ReadFileText(dir / "c/images/view_00.jpg"));

  const std::string synth = Quote(StageBinary("synth").string()) + " " + kTiny;
  CommandResult r =
      RunCommand(synth + " --kind text --roll 58 --out " + Quote((dir / "x").string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--roll is for --kind receipt"), std::string::npos) << r.output;
  r = RunCommand(synth + " --flap end --steep-fold 120 --end-curl both --out " +
                 Quote((dir / "x").string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("needs an end of the page"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "x"));
}

}  // namespace
}  // namespace docunfold::testing
