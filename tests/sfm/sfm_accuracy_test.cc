// sfm against the ground truth of every data set (samples/* and
// ../shared/realistic/*): all checks on one run per data set, the run the
// end-to-end fixture made (build/e2e/work/<set>/10_sfm, see tests/pipeline),
// or a run of its own when that is absent.
//   - every view registered;
//   - camera centres within 1 % of the page diagonal (RMS, after a similarity
//     alignment of the sfm centres onto the true ones, Eigen::umeyama);
//   - median distance of the points on the page to the true surface within
//     0.5 % of the diagonal, and the camera centres still within 1 %, after
//     the similarity that fits cameras and page together ("on the page": the
//     point falls on the true page in at least half of the true views whose
//     image it falls in; points on a textured table are real points, just
//     not of the page); within 1 % after the cameras' similarity alone;
//   - a sensible reference: it sees the whole page when some view does, and
//     is about as frontal as the most frontal such view;
//   - the files are what later stages expect (schema, reference frame, median
//     depth 1, reference.png at the camera's size, COLMAP's model readable).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>

#include "common/json_io.h"
#include "common/option_table.h"
#include "common/subprocess.h"
#include "stages/sfm/sfm.h"
#include "tests/sfm/sfm_eval.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

constexpr double kMaxCameraRms = 0.01;        // of the page diagonal
constexpr double kMaxMedianDistance = 0.005;  // of the page diagonal
// After the cameras' similarity alone. With 4 views a common tilt of all
// cameras of 0.06 deg moves the page 2 mm along its normal relative to their
// centres (see stages/sfm/sfm.cc), and COLMAP seeds its RANSAC afresh each
// run: twelve runs of sfm on r02 with the same code measured 0.17-0.55 % here
// (3 above 0.5 %) and 0.08-0.20 % for the page, 0.08-0.15 % for the cameras
// under the joint fit. So this gauge keeps a bound for gross errors only
// (r03's solution bent by wrong matches reached 2.6 %).
constexpr double kMaxCameraGaugeMedianDistance = 0.01;
// The reference's true resolution where it sees the page worst (10 %
// quantile of pixels per metre across the foreshortening, hidden parts 0) is
// at least this fraction of the best whole-page view's. sfm estimates it from
// the sparse page points, which miss blank and curled parts: measured, the
// chosen view is the truly best on 9 of 12 sets, 0.81 of it on r03 and 0.43
// on set02 (a curled corner with few points). The most frontal view, chosen
// before, reached 0.35 (set01), 0.06 (set05) and 0 (set02, set07: part of
// the page seen from behind), which this bound rejects.
constexpr double kResolutionFraction = 0.4;

class SfmAccuracy : public ::testing::TestWithParam<fs::path> {};

TEST_P(SfmAccuracy, MatchesGroundTruth) {
  const fs::path dataset = GetParam();
  const std::string name = SfmDataSetName(dataset);
  const auto gt = LoadGroundTruth(dataset);
  ASSERT_TRUE(gt);
  TempDir tmp;
  sfm::SfmOptions options;
  options.data_dir = dataset;
  options.out_dir = tmp / "10_sfm";
  const auto start = std::chrono::steady_clock::now();
  const fs::path e2e =
      fs::path(DOCUNFOLD_BIN_DIR).parent_path() / "e2e/work" / dataset.filename() / "10_sfm";
  if (const char* dir = std::getenv("DOCUNFOLD_SFM_MEASURE_DIR")) {
    options.out_dir = fs::path(dir) / dataset.filename() / "10_sfm";
  } else if (fs::is_regular_file(e2e / "cameras.json")) {
    options.out_dir = e2e;
  } else {
    CLI::App app;
    OptionTable table(app);
    sfm::DeclareOptions(table, &options);  // the defaults, as the record of cameras.json
    ASSERT_NO_THROW(sfm::RunSfm(options, table.Record())) << name;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const SfmFigures f = MeasureSfm(options.out_dir, *gt);
  const Json doc = ReadJsonFile(options.out_dir / "cameras.json");
  std::printf("[sfm] %s: %s; %s f=%.1f px; %.1f s\n", name.c_str(), FormatFigures(f).c_str(),
              doc.at("colmap").at("camera_model").get<std::string>().c_str(),
              doc.at("colmap").at("cameras").at(0).at("params").at(0).get<double>(), seconds);
  RecordProperty("figures", FormatFigures(f));

  EXPECT_EQ(f.registered, f.views) << name;
  EXPECT_LE(f.camera_rms, kMaxCameraRms) << name;
  EXPECT_GE(f.page_points, 100) << name;
  EXPECT_LE(f.joint_median_distance, kMaxMedianDistance) << name;
  EXPECT_LE(f.joint_camera_rms, kMaxCameraRms) << name;
  EXPECT_LE(f.median_page_distance, kMaxCameraGaugeMedianDistance) << name;
  if (!f.best_true_view.empty()) {
    EXPECT_TRUE(f.reference_whole_page)
        << name << ": reference " << f.reference << " cuts the page off, " << f.best_true_view
        << " shows all of it";
    EXPECT_GE(f.reference_resolution, kResolutionFraction * f.best_true_resolution)
        << name << ": reference " << f.reference << " vs " << f.best_true_view;
  }

  // The files later stages read.
  const CameraSet cameras = ReadCameras(options.out_dir / "cameras.json");
  const PinholeCamera* ref = cameras.Find(cameras.reference);
  ASSERT_NE(ref, nullptr);
  EXPECT_TRUE(ref->R.isIdentity(1e-12)) << name;
  EXPECT_TRUE(ref->t.isZero(1e-12)) << name;
  EXPECT_NEAR(f.reference_median_depth, 1.0, 0.1) << name;
  const cv::Mat png = cv::imread((options.out_dir / "reference.png").string());
  EXPECT_EQ(png.cols, ref->width) << name;
  EXPECT_EQ(png.rows, ref->height) << name;
  const PlyData ply = ReadPly(options.out_dir / "points.ply");
  EXPECT_EQ(ply.colors.size(), ply.vertices.size());
  EXPECT_NE(ply.FindProperty("track_length"), nullptr);
  EXPECT_NE(ply.FindProperty("reprojection_error"), nullptr);
  const CommandResult schema =
      RunCommand(Quote((SourceDir() / "scripts" / "validate-json").string()) +
                 " --format "
                 "docunfold.cameras " +
                 Quote((options.out_dir / "cameras.json").string()));
  EXPECT_EQ(schema.exit_code, 0) << schema.output;
  if (!FindExecutable("colmap").empty()) {
    const CommandResult analyzer =
        RunCommand("colmap model_analyzer --path " +
                   Quote((options.out_dir / "colmap" / "sparse" / "0").string()));
    EXPECT_EQ(analyzer.exit_code, 0) << analyzer.output;
    EXPECT_NE(analyzer.output.find("Registered images: " + std::to_string(f.registered)),
              std::string::npos)
        << analyzer.output;
  }
}

std::string ParamName(const ::testing::TestParamInfo<fs::path>& info) {
  std::string s = SfmDataSetName(info.param);
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(DataSets, SfmAccuracy, ::testing::ValuesIn(SfmDataSets()), ParamName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(SfmAccuracy);

}  // namespace
}  // namespace docunfold::testing
