// End-to-end checks of every stage against the ground truth of every data set,
// on the one run of the whole pipeline that run_e2e.sh makes (CTest fixture
// e2e_run; sfm's cameras and points are checked by tests/sfm on the same
// run): the boundary and the feature segments
// in the reference view, the meshes, the metrics of the result next to the
// homography and oracle rows, and that other tools read our files (assimp,
// the Khronos glTF validator, COLMAP, headless chromium for the report).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/camera.h"
#include "common/json_io.h"
#include "common/page_files.h"
#include "common/ply.h"
#include "common/raster.h"
#include "tests/boundary/eval_support.h"
#include "tests/support/ground_truth.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

// The data sets run_e2e.sh runs, by the name of their work directory.
std::vector<std::string> E2eSets() {
  std::vector<std::string> names;
  for (const fs::path& d : DataSetsWithTruth())
    if (fs::is_regular_file(d / "ground_truth/flat.png")) names.push_back(d.filename().string());
  return names;
}

fs::path DataDir(const std::string& name) {
  for (const fs::path& d : DataSetsWithTruth())
    if (d.filename() == name) return d;
  return {};
}

std::string Tool(const std::string& script) {
  return Quote((SourceDir() / "tests/tools" / script).string());
}

// The exit code of the e2e run's pipeline in `work` (scripts/bench.sh writes
// it), or -1 when it did not record one.
int PipelineExit(const fs::path& work) {
  std::ifstream exit_file(work / "bench/pipeline.exit");
  int status = -1;
  exit_file >> status;
  return status;
}

// Similarity taking the true world to sfm's world: x_sfm = s R x_true + t.
struct Similarity {
  double s = 1;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d ToTrue(const Eigen::Vector3d& x) const { return R.transpose() * (x - t) / s; }
};

class EndToEnd : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    set_ = GetParam();
    data_ = DataDir(set_);
    work_ = E2eDir() / "work" / set_;
    ASSERT_TRUE(fs::is_directory(work_)) << work_ << " (did the e2e_run fixture run?)";
    ASSERT_EQ(PipelineExit(work_), 0)
        << set_ << ": the pipeline failed; see " << work_ / "bench/pipeline.log";
    auto gt = LoadGroundTruth(data_);
    ASSERT_TRUE(gt);
    gt_ = std::move(*gt);
    sfm_ = ReadCameras(work_ / "10_sfm/cameras.json");
    AlignCameras();
  }

  // Umeyama on the camera centres.
  void AlignCameras() {
    std::vector<Eigen::Vector3d> a, b;
    for (const PinholeCamera& c : sfm_.views)
      if (const PinholeCamera* t = gt_.cameras.Find(c.image)) {
        a.push_back(t->Center());
        b.push_back(c.Center());
      }
    ASSERT_GE(a.size(), 2u);
    Eigen::Matrix3Xd A(3, a.size()), B(3, b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      A.col(i) = a[i];
      B.col(i) = b[i];
    }
    const Eigen::Matrix4d T = Eigen::umeyama(A, B, true);
    sim_.s = T.block<3, 1>(0, 0).norm();
    sim_.R = T.block<3, 3>(0, 0) / sim_.s;
    sim_.t = T.block<3, 1>(0, 3);
    double sq = 0;
    for (size_t i = 0; i < a.size(); ++i) sq += (sim_.ToTrue(b[i]) - a[i]).squaredNorm();
    centre_rms_ = std::sqrt(sq / a.size());
  }

  std::string set_;
  fs::path data_, work_;
  GroundTruth gt_;
  CameraSet sfm_;
  Similarity sim_;
  double centre_rms_ = 0;
};

// The front end in sfm's reference view, as the benchmark measured it
// (evaluate --front-end, 70_eval/front_end.json; the truth moved into
// reference.png by sfm's own undistortion, so the figures judge the stages
// and not sfm's calibration).
Json FrontEnd(const fs::path& work) {
  const fs::path file = work / "70_eval/front_end.json";
  EXPECT_TRUE(fs::exists(file)) << file << " (evaluate --front-end did not run)";
  return fs::exists(file) ? ReadJsonFile(file) : Json::object();
}

TEST_P(EndToEnd, BoundaryMatchesThePageInTheReferenceView) {
  const Json doc = FrontEnd(work_);
  ASSERT_TRUE(doc.contains("boundary") && doc["boundary"].contains("iou")) << set_;
  const Json& f = doc["boundary"];
  std::printf(
      "%s (%s): boundary IoU %.4f, worst visible corner %.2f %% of the diagonal%s, "
      "%d side(s) not real%s\n",
      set_.c_str(), doc.value("reference", "").c_str(), f["iou"].get<double>(),
      100 * f["worst_corner_fraction"].get<double>(),
      f["corner_hidden"].get<bool>() ? " (a corner hidden)" : "", f["sides_not_real"].get<int>(),
      f["page_cut"].get<bool>() ? " (page cut)" : "");
  RecordProperty("iou", std::to_string(f["iou"].get<double>()));
  RecordProperty("worst_corner_pct",
                 std::to_string(100 * f["worst_corner_fraction"].get<double>()));
  // IoU and the cut flags are asserted; corners are printed (tests/boundary
  // asserts them in each set's most frontal view): sfm picks a view by its
  // points, and in some (set08's view_00) a fold's kink is the sharpest turn.
  EXPECT_GE(f["iou"].get<double>(), 0.97) << set_;
  if (f["page_cut"].get<bool>()) {
    EXPECT_GE(f["sides_not_real"].get<int>(), 1)
        << set_ << ": the page is cut off, some side is not real";
  }
  // A side flagged not real runs along the image border for most of its
  // length (its simplified polyline may end in a few short vertices where
  // the outline leaves the border, so count length, not vertices).
  const Boundary b = ReadBoundary(work_ / "20_boundary/boundary.json");
  auto near_border = [&](const Eigen::Vector2d& p) {
    return p.x() < 4 || p.y() < 4 || p.x() > b.width - 5 || p.y() > b.height - 5;
  };
  for (const BoundarySide& s : b.sides) {
    if (s.real) continue;
    double along = 0, total = 0;
    for (size_t k = 1; k < s.points.size(); ++k) {
      const double l = (s.points[k] - s.points[k - 1]).norm();
      total += l;
      if (near_border(s.points[k]) && near_border(s.points[k - 1])) along += l;
    }
    EXPECT_GE(along, 0.5 * total) << set_;
  }
}

TEST_P(EndToEnd, FeatureSegmentsLieOnTrueLines) {
  const Json doc = FrontEnd(work_);
  ASSERT_TRUE(doc.contains("features") && doc["features"].contains("precision")) << set_;
  const Json& f = doc["features"];
  std::printf(
      "%s (%s): %d text and %d edge segments, precision %.3f, recall %.3f (text %.3f, "
      "rules %.3f)%s\n",
      set_.c_str(), doc.value("reference", "").c_str(), f["text_segments"].get<int>(),
      f["edge_segments"].get<int>(), f["precision"].get<double>(), f["recall"].get<double>(),
      f["recall_text"].get<double>(), f["recall_rule"].get<double>(),
      f["recall_required"].get<bool>() ? " (text page or table)" : "");
  // The front end's targets (docs/decisions/pipeline.md, "Front-end targets"), in sfm's
  // reference view of this run.
  EXPECT_GE(f["precision"].get<double>(), 0.95) << set_;
  if (f["recall_required"].get<bool>()) {
    EXPECT_GE(f["recall"].get<double>(), 0.5) << set_;
  }
}

// densify leaves out sfm points that the reference view shows in another
// colour: table seen behind a raised part of the page by the other photos.
// Before that rule, 26 % of set02's sfm points in the page region were more
// than 3 % of the diagonal off the true surface (its raised flap) and 11 % of
// set04's; after it, at most 3.7 % on every set over two sfm runs.
TEST_P(EndToEnd, SfmPointsKeptOnThePageLieOnTheTrueSurface) {
  const PlyData points = ReadPly(work_ / "25_points/points.ply");
  const PlyProperty* source = points.FindProperty("source");
  ASSERT_NE(source, nullptr);
  const cv::Mat1b region = ContourRegion(ReadBoundary(work_ / "20_boundary/boundary.json"), 0);
  const std::vector<int> inside =
      PointsInRegion(points.vertices, *sfm_.Find(sfm_.reference), region);
  int sfm = 0, off = 0;
  for (const int i : inside) {
    if (source->values[i] != 0) continue;
    const Eigen::Vector3d x = sim_.ToTrue(points.vertices[i]);
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& v : gt_.mesh.vertices)
      nearest = std::min(nearest, (v - x).squaredNorm());
    ++sfm;
    off += std::sqrt(nearest) > 0.03 * gt_.Diagonal();
  }
  std::printf(
      "%s: %d of %d sfm points on the page more than 3 %% of the diagonal off the true "
      "surface\n",
      set_.c_str(), off, sfm);
  ASSERT_GT(sfm, 0) << set_;
  EXPECT_LE(off, 0.08 * sfm) << set_;
}

// Whether a binary PLY's first data byte is '\n', which assimp 5.2's PLY
// reader skips, shifting everything after it (assimp's bug tracker, #5341): it then
// reports a valid file as broken (seen on r03, whose first vertex's x began
// with 0x0a; '\r', '\f' and '\0' there are read correctly).
bool AssimpMisreadsBinaryPly(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t end = bytes.find("end_header\n");
  if (end == std::string::npos || end + 11 >= bytes.size()) return false;
  return bytes[end + 11] == '\n';
}

TEST_P(EndToEnd, MeshesAreCloseToTheTruthAndReadable) {
  const auto rows = E2eRows(set_);
  const double init_surface = Metric(rows, "docunfold-init", "surface_mean_pct");
  const double init_iso = Metric(rows, "docunfold-init", "isometry_mean");
  const double final_surface = Metric(rows, "docunfold", "surface_mean_pct");
  const double final_iso = Metric(rows, "docunfold", "isometry_mean");
  std::printf(
      "%s: M to the true surface %.3f %% (init) %.3f %% (final) of the diagonal; "
      "isometry error %.4f / %.4f\n",
      set_.c_str(), init_surface, final_surface, init_iso, final_iso);
  // Targets: M within 1 % of the page diagonal of the true surface and an isometry error
  // under 0.005 for init-mesh; optimize must not move M away from the truth beyond the
  // run-to-run spread of sfm, so the final M may be half the init's distance farther
  // (docs/decisions/pipeline.md, "Geometry bounds in the end-to-end test").
  EXPECT_LT(init_surface, 1.0) << set_;
  EXPECT_LE(final_surface, 3.0) << set_;
  EXPECT_LE(final_surface, 1.5 * init_surface + 0.1) << set_;
  EXPECT_LT(init_iso, 0.01) << set_;
  EXPECT_LT(final_iso, 0.03) << set_;
  // The mesh is never the grid over the mask's bounding box.
  const std::string grid_source = ReadJsonFile(work_ / "40_init/init.json")["grid"]["source"];
  EXPECT_NE(grid_source, "mask_bbox") << set_;
  // Every PLY of the run opens in an independent reader.
  for (const char* f : {"40_init/mesh3d.ply", "40_init/mesh2d.ply", "50_optimize/mesh3d.ply",
                        "50_optimize/mesh2d.ply", "50_optimize/round0/mesh3d.ply"}) {
    if (AssimpMisreadsBinaryPly(work_ / f)) {
      std::printf(
          "%s: %s starts its data with a 0x0a byte, which assimp 5.2 skips "
          "(assimp#5341); read with our reader instead\n",
          set_.c_str(), f);
      EXPECT_GT(ReadPly(work_ / f).vertices.size(), 0u) << f;
      continue;
    }
    CommandResult r = RunCommand("assimp info " + Quote((work_ / f).string()));
    EXPECT_EQ(r.exit_code, 0) << f << "\n" << r.output;
  }
  // The point cloud too: assimp's validation refuses a mesh without faces,
  // so it is read raw, and must hold every point.
  {
    const PlyData points = ReadPly(work_ / "10_sfm/points.ply");
    CommandResult r =
        RunCommand("assimp info " + Quote((work_ / "10_sfm/points.ply").string()) + " --raw");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const size_t at = r.output.find("Vertices:");
    ASSERT_NE(at, std::string::npos) << r.output;
    EXPECT_EQ(std::stol(r.output.substr(at + 9)), long(points.vertices.size())) << r.output;
  }
  PlyData m = ReadPly(work_ / "50_optimize/mesh3d.ply");
  EXPECT_TRUE(m.CommentValue("TextureFile").has_value());
  EXPECT_NE(m.FindProperty("texture_u"), nullptr);
}

TEST_P(EndToEnd, OptimizeLowersFWithinEveryRound) {
  const Json log = ReadJsonFile(work_ / "50_optimize/log.json");
  ASSERT_EQ(log.at("rounds").size(), 4u);
  for (const Json& round : log["rounds"]) {
    const Json& it = round.at("iterations");
    ASSERT_FALSE(it.empty());
    const double first = it.front().at("F"), last = it.back().at("F");
    // Every step lowers F on the data it was taken with.
    for (const Json& i : it)
      if (i.contains("F_after_step")) {
        EXPECT_LE(i["F_after_step"].get<double>(), i.at("F").get<double>() * (1 + 1e-9))
            << set_ << " round " << round.value("round", -1) << " iteration " << i["iteration"];
      }
    // Between iterations footpoints, outliers and the feature markers are re-decided (and
    // the markers projected onto their lines, which moves them off their rays), so F from
    // one iteration to the next is not one function and not monotone: it falls within a
    // step (asserted above); across a round it must not run away.
    EXPECT_LE(last, first * 8) << set_ << " round " << round.value("round", -1);
  }
}

TEST_P(EndToEnd, ResultIsBetterThanTheReferenceMethods) {
  const auto rows = E2eRows(set_);
  const double ours = Metric(rows, "docunfold", "ms_ssim");
  const double init = Metric(rows, "docunfold-init", "ms_ssim");
  const double homography = Metric(rows, "homography", "ms_ssim");
  const double oracle = Metric(rows, "oracle", "ms_ssim");
  std::printf(
      "%s: MS-SSIM docunfold %.4f, init %.4f, homography %.4f, oracle %.4f; LD "
      "docunfold %.2f\n",
      set_.c_str(), ours, init, homography, oracle, Metric(rows, "docunfold", "ld"));
  ASSERT_FALSE(std::isnan(ours)) << set_ << ": no docunfold row";
  RecordProperty("ms_ssim", std::to_string(ours));
  // docunfold and docunfold-init beat the homography on every set in the benchmark, but by
  // little on set07 in some sfm runs, and docunfold comes within 0.01 of its init or below it
  // there (docs/decisions/pipeline.md, "Where set07 loses to its init"): not asserted.
  // Asserted: a real page comes out, and the oracle row is sound.
  EXPECT_GT(ours, 0.25) << set_;
  EXPECT_GT(oracle, homography + 0.05) << set_ << ": the oracle should clearly beat homography";
  // The light's shading divided out (render/baseline --shading remove) never costs the page.
  const double deshaded = Metric(rows, "docunfold-deshaded", "ms_ssim");
  const double oracle_deshaded = Metric(rows, "oracle-deshaded", "ms_ssim");
  std::printf("%s: MS-SSIM with the shading removed: docunfold %.4f, oracle %.4f\n", set_.c_str(),
              deshaded, oracle_deshaded);
  ASSERT_FALSE(std::isnan(deshaded)) << set_ << ": no docunfold-deshaded row";
  ASSERT_FALSE(std::isnan(oracle_deshaded)) << set_ << ": no oracle-deshaded row";
  EXPECT_GE(deshaded, ours - 0.01) << set_;
  EXPECT_GE(oracle_deshaded, oracle - 0.01) << set_;
}

// segment-boundary finds the page in the other photos too; where the
// reference image cuts the page off, render takes the crop past the cut border
// as far as they show page and textures that part from them (set08: its
// right edge, seen by all three other photos, and 11-12 % more at the top,
// whose edge none of them sees).
TEST_P(EndToEnd, OtherViewsShowThePagePastTheReferenceImage) {
  int masks = 0, others = 0;
  for (const PinholeCamera& view : sfm_.views) {
    if (view.image == sfm_.reference) continue;
    ++others;
    masks +=
        fs::is_regular_file(work_ / "20_boundary/views" / fs::path(view.image).stem() / "mask.png");
  }
  EXPECT_EQ(masks, others) << set_;
  const Json render = ReadJsonFile(work_ / "60_render/render.json");
  int cut = 0, extended = 0;
  for (const char* side : {"top", "right", "bottom", "left"}) {
    const Json& s = render["sides"][side];
    if (s["real"].get<bool>()) continue;
    ++cut;
    ASSERT_TRUE(s.contains("page_edge_in_other_views")) << set_ << " " << side;
    const Json& e = s["page_edge_in_other_views"];
    if (e["measured"].get<bool>() && e.value("extension", 0.0) > 0) ++extended;
  }
  const double textured = render.value("other_view_fraction", 0.0);
  std::printf(
      "%s: %d of %d other views' page masks; %d cut sides, %d extended; %.3f of the "
      "result from other views\n",
      set_.c_str(), masks, others, cut, extended, textured);
  // Whether a view's texture is used depends on how well it registers with
  // the reference's (set08: 0.09-0.15 of the result over four sfm runs), so
  // only the extension is asserted; the texturing has a unit test.
  if (cut > 0) {
    EXPECT_GE(extended, 1) << set_;
  } else {
    EXPECT_EQ(textured, 0.0) << set_;
  }
}

// The first and the last line of text some photo shows (a receipt's header and
// total) map into the result: a crop that stops at a fold or a curl, or a mesh
// that ends short of the page's end, loses them. Each line is sampled every 4
// flat.png pixels and carried to sfm's world through the true surface; a
// point the reference photo sees maps through the mesh M under its pixel there
// (what render samples), another through the nearest vertex of M, which must
// lie within 1 % of the page diagonal; then through M' into the crop. Pages
// cut off in the reference photo are left out: there the crop ends where
// the photos' view of the page ends.
TEST_P(EndToEnd, FirstAndLastLinesOfTextAreInTheResult) {
  struct Sampled {
    double mean_y = 0;
    std::vector<Eigen::Vector2d> flat;
    std::vector<bool> seen, seen_by_reference;
  };
  const Boundary boundary = ReadBoundary(work_ / "20_boundary/boundary.json");
  for (const auto& side : boundary.sides)
    if (!side.real)  // OtherViewsShowThePagePastTheReferenceImage covers a page cut off there
      GTEST_SKIP() << set_ << ": the page is cut off in the reference photo";
  const PinholeCamera* reference = sfm_.Find(sfm_.reference);
  ASSERT_NE(reference, nullptr) << set_;
  const PinholeCamera* true_reference = gt_.cameras.Find(sfm_.reference);
  ASSERT_NE(true_reference, nullptr) << set_;
  std::vector<Sampled> lines;
  for (const TrueLine& l : TruthLines(gt_)) {
    if (l.kind != "text") continue;
    Sampled s;
    for (size_t k = 0; k + 1 < l.points.size(); ++k) {
      const Eigen::Vector2d a = l.points[k], b = l.points[k + 1];
      const int n = std::max(1, int(std::ceil((b - a).norm() / 4.0)));
      for (int j = (k == 0 ? 0 : 1); j <= n; ++j) s.flat.push_back(a + (b - a) * (double(j) / n));
    }
    for (const Eigen::Vector2d& p : s.flat) s.mean_y += p.y() / s.flat.size();
    s.seen.assign(s.flat.size(), false);
    s.seen_by_reference.assign(s.flat.size(), false);
    if (!s.flat.empty()) lines.push_back(std::move(s));
  }
  if (lines.empty()) GTEST_SKIP() << set_ << ": no text lines in the truth";
  for (const PinholeCamera& camera : gt_.cameras.views)  // one rasterization per camera
    for (Sampled& s : lines)
      for (size_t i = 0; i < s.flat.size(); ++i) {
        if (s.seen[i] && camera.image != true_reference->image) continue;
        const bool seen = TruePointSeen(gt_, camera, s.flat[i]);
        s.seen[i] = s.seen[i] || seen;
        if (camera.image == true_reference->image) s.seen_by_reference[i] = seen;
      }
  std::vector<const Sampled*> shown;
  for (const Sampled& s : lines)
    if (std::count(s.seen.begin(), s.seen.end(), true) >= 0.9 * s.seen.size()) shown.push_back(&s);
  if (shown.empty()) GTEST_SKIP() << set_ << ": no line of text seen whole in any photo";
  auto by_y = [](const Sampled* a, const Sampled* b) { return a->mean_y < b->mean_y; };
  const Sampled* first = *std::min_element(shown.begin(), shown.end(), by_y);
  const Sampled* last = *std::max_element(shown.begin(), shown.end(), by_y);

  const PlyData m3 = ReadPly(work_ / "50_optimize/mesh3d.ply");
  const PlyData m2 = ReadPly(work_ / "50_optimize/mesh2d.ply");
  ASSERT_EQ(m3.vertices.size(), m2.vertices.size()) << set_;
  const std::vector<Triangle> triangles = Triangulate(m3.faces);
  const RasterResult in_reference = RasterizeMesh(*reference, m3.vertices, triangles);
  const Json render = ReadJsonFile(work_ / "60_render/render.json");
  const Json& crop = render.at("crop");
  const Eigen::Rotation2Dd rotation(render.at("rotation_deg").get<double>() * M_PI / 180);
  const double reach = 0.01 * gt_.Diagonal() * sim_.s;
  // M' position of sfm-world point x, if M reaches it.
  auto on_flat_mesh = [&](const Eigen::Vector3d& x,
                          bool by_reference) -> std::optional<Eigen::Vector2d> {
    if (by_reference) {
      const Eigen::Vector3d xc = reference->CamFromWorld(x);
      const Eigen::Vector2d px = reference->ProjectCam(xc);
      const int u = int(std::lround(px.x())), v = int(std::lround(px.y()));
      if (!(xc.z() > 0) || u < 0 || v < 0 || u >= in_reference.face.cols ||
          v >= in_reference.face.rows || in_reference.face(v, u) < 0)
        return std::nullopt;
      const Triangle& t = triangles[in_reference.face(v, u)];
      const cv::Vec2f b = in_reference.bary(v, u);
      return ((1 - b[0] - b[1]) * m2.vertices[t[0]] + b[0] * m2.vertices[t[1]] +
              b[1] * m2.vertices[t[2]])
          .head<2>();
    }
    size_t best = 0;
    double best_d2 = std::numeric_limits<double>::infinity();
    for (size_t v = 0; v < m3.vertices.size(); ++v) {
      const double d2 = (m3.vertices[v] - x).squaredNorm();
      if (d2 < best_d2) best_d2 = d2, best = v;
    }
    if (std::sqrt(best_d2) > reach) return std::nullopt;
    return m2.vertices[best].head<2>();
  };
  for (const Sampled* line : {first, last}) {
    int checked = 0, off_mesh = 0, outside = 0;
    for (size_t i = 0; i < line->flat.size(); ++i) {
      const auto x_true = gt_.SurfacePoint(line->flat[i]);
      if (!line->seen[i] || !x_true) continue;
      ++checked;
      const auto flat =
          on_flat_mesh(sim_.s * (sim_.R * *x_true) + sim_.t, line->seen_by_reference[i]);
      if (!flat) {
        ++off_mesh;
        continue;
      }
      const Eigen::Vector2d q = rotation * *flat;
      if (q.x() < crop.at("x0").get<double>() || q.x() > crop.at("x1").get<double>() ||
          q.y() < crop.at("y0").get<double>() || q.y() > crop.at("y1").get<double>())
        ++outside;
    }
    const char* which = line == first ? "first" : "last";
    std::printf("%s: %s line of text at flat y %.0f: %d points, %d off M, %d outside the crop\n",
                set_.c_str(), which, line->mean_y, checked, off_mesh, outside);
    ASSERT_GT(checked, 0) << set_;
    EXPECT_LE(off_mesh + outside, 0.05 * checked) << set_ << ": the " << which << " line";
  }
}

TEST_P(EndToEnd, OtherToolsReadOurFiles) {
  CommandResult r = RunCommand("node " + Tool("validate-gltf.js") + " " +
                               Quote((work_ / "50_optimize/scene.glb").string()));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = RunCommand("colmap model_analyzer --path " +
                 Quote((work_ / "10_sfm/colmap/sparse/0").string()));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // Every JSON file the stages wrote, in one run of the validator (it names
  // the file of each problem; one run per file cost 5 s per set).
  std::string files;
  int count = 0;
  for (const auto& e : fs::recursive_directory_iterator(work_)) {
    const std::string p = e.path().string();
    if (e.path().extension() != ".json" || p.find("/colmap/") != std::string::npos ||
        p.find("/bench/") != std::string::npos)
      continue;
    files += " " + Quote(p);
    ++count;
  }
  EXPECT_GE(count, 10) << "too few JSON files in " << work_;
  r = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + files);
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

INSTANTIATE_TEST_SUITE_P(Sets, EndToEnd, ::testing::ValuesIn(E2eSets()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(EndToEnd);

// Every set's report, made from its run, opened in one headless Chromium (the
// browser's start costs as much as a page, a screenshot twice as much: one is
// kept, build/e2e/reports/screenshot.png).
TEST(EndToEndSummary, EveryReportOpensInHeadlessChromium) {
  const fs::path out = E2eDir() / "reports";
  fs::create_directories(out);
  std::string reports;
  std::vector<std::string> sets;
  for (const std::string& set : E2eSets()) {
    const fs::path work = E2eDir() / "work" / set;
    if (PipelineExit(work) != 0) continue;  // Sets/EndToEnd names the set whose pipeline failed
    const fs::path report = out / (set + ".html");
    const CommandResult r = RunCommand(Quote(StageBinary("report").string()) + " --data " +
                                       Quote(DataDir(set).string()) + " --work " +
                                       Quote(work.string()) + " --out " + Quote(report.string()));
    EXPECT_EQ(r.exit_code, 0) << set << ": " << r.output;
    if (r.exit_code != 0) continue;
    reports += " " + Quote(report.string());
    sets.push_back(set);
  }
  if (sets.empty()) GTEST_SKIP() << "no set's pipeline ran";
  const CommandResult r = RunCommand("node " + Tool("check-report.js") + " " +
                                     Quote((out / "screenshot.png").string()) + reports);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const Json summaries = Json::parse(r.output.substr(std::min(r.output.find('['), r.output.size())),
                                     nullptr, /*allow_exceptions=*/false);
  ASSERT_TRUE(summaries.is_array() && summaries.size() == sets.size()) << r.output;
  for (size_t i = 0; i < sets.size(); ++i) {
    const Json& s = summaries[i];
    EXPECT_TRUE(s.value("ok", false)) << sets[i] << ": " << s.dump(1);
    const std::string sections = s.value("sections", Json::array()).dump();
    for (const char* part : {"Photos and the reference view", "Boundary and feature segments",
                             "Point cloud and meshes", "Convergence of the optimisation",
                             "The rectified page", "Stages: time, memory and flags"})
      EXPECT_NE(sections.find(part), std::string::npos) << sets[i] << ": " << part;
  }
}

// Across the samples: the means over the whole set.
TEST(EndToEndSummary, SamplesOnAverage) {
  const Json results = ReadJsonFile(E2eDir() / "results.json");
  double ours = 0, oracle = 0, oracle_seen = 0, ld = 0, ld_whole = 0;
  int n = 0, n_whole = 0;
  for (const Json& s : results.at("sets")) {
    const std::string name = s.value("name", "");
    if (!fs::is_directory(SampleDir(name))) continue;
    const auto rows = E2eRows(name);
    ours += Metric(rows, "docunfold", "ms_ssim");
    oracle += Metric(rows, "oracle", "ms_ssim");
    oracle_seen += Metric(rows, "oracle-seen", "ms_ssim");
    const double set_ld = Metric(rows, "docunfold", "ld");
    ld += set_ld;
    ++n;
    // A page cut off in the photos (synth --cut-off) is scored against the
    // whole page, part of which no photo shows: its LD measures where that
    // part was guessed to be more than how the seen part was flattened.
    const bool cut_off =
        ReadJsonFile(SampleDir(name) / "ground_truth/synth.json")["producer"]["options"].value(
            "cut_off", false);
    if (!cut_off) {
      ld_whole += set_ld;
      ++n_whole;
    }
  }
  ASSERT_GT(n, 0);
  ASSERT_GT(n_whole, 0);
  std::printf(
      "samples: mean MS-SSIM docunfold %.4f, oracle %.4f, oracle cropped to what the photos "
      "see %.4f; mean LD %.2f (%.2f over the %d pages seen whole)\n",
      ours / n, oracle / n, oracle_seen / n, ld / n, ld_whole / n_whole, n_whole);
  // Targets: the samples' mean MS-SSIM within 0.05 of the oracle cropped to the part of the
  // page some photo sees (baseline --crop-to-seen: the ceiling for a method that has only the
  // photos when a page is cut off in all of them) and a mean LD of at most 2 where the whole
  // page is seen. Asserted: the margin against that ceiling, and no regression beyond the
  // spread of sfm runs, with a margin for two sets' swing at once
  // (docs/decisions/pipeline.md, "The samples' means in the end-to-end test").
  EXPECT_FALSE(std::isnan(ours));
  EXPECT_FALSE(std::isnan(oracle_seen)) << "no oracle-seen row";
  EXPECT_GT(ours / n, oracle_seen / n - 0.05);
  EXPECT_GT(ours / n, 0.76);
  EXPECT_LT(ld / n, 3.2);
  EXPECT_LT(ld_whole / n_whole, 2.5);
}

}  // namespace
}  // namespace docunfold::testing
