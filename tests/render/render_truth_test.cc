// Rendering the TRUE meshes of every data set with ground truth reproduces
// ground_truth/flat.png: the crop is the page (or, for a cut-off page, is
// bounded by its real sides), and the content is where flat.png has it.
#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "stages/render/render.h"
#include "tests/render/render_fixtures.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

class RenderTruth : public ::testing::TestWithParam<fs::path> {};

// flat.png in the frame of the rendered image: render pixel (i, j) shows the
// point (x0 + (i + 0.5) / sx, y0 + (j + 0.5) / sy) of M', and the true M' is
// flat.png scaled by `units_per_flat_px`.
cv::Mat FlatInRenderFrame(const cv::Mat& flat, double units_per_flat_px,
                          const render::RenderResult& r) {
  // render px per flat px
  const double fx = r.pixels_per_unit * units_per_flat_px;
  const double fy = r.pixels_per_unit_y * units_per_flat_px;
  cv::Mat small;
  cv::resize(flat, small, cv::Size(), fx, fy, fx < 1 ? cv::INTER_AREA : cv::INTER_CUBIC);
  // Pixel k of `small` is centred on flat coordinate (k + 0.5) / sx - 0.5
  // (resize's convention), i.e. on M' x = (k + 0.5) / sx * units_per_flat_px;
  // render pixel i on x0 + (i + 0.5) / s. Solved for k:
  const double sx = double(small.cols) / flat.cols, sy = double(small.rows) / flat.rows;
  const double ax = sx / fx, ay = sy / fy;
  const cv::Matx23d render_to_small(ax, 0, 0.5 * ax - 0.5 + ax * r.pixels_per_unit * r.crop_x0, 0,
                                    ay, 0.5 * ay - 0.5 + ay * r.pixels_per_unit_y * r.crop_y0);
  cv::Mat out;
  cv::warpAffine(small, out, render_to_small, r.rectified.size(),
                 cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  return out;
}

TEST_P(RenderTruth, TrueMeshesReproduceFlatPng) {
  const fs::path set = GetParam();
  auto gt = LoadGroundTruth(set);
  ASSERT_TRUE(gt);
  const render::RenderInputs in = InputsOf(MakeTruthInputs(*gt));
  const render::RenderResult r = render::Run({}, in);
  ASSERT_FALSE(r.rectified.empty());

  // The true M' is the page [0, W] x [0, H] in its units.
  double page_w = 0, page_h = 0;
  for (const auto& q : in.meshes.mesh2d) {
    page_w = std::max(page_w, q.x());
    page_h = std::max(page_h, q.y());
  }
  const double diag = std::hypot(page_w, page_h);
  EXPECT_NEAR(page_w / page_h, gt->width_m / gt->height_m, 1e-3);
  const double true_edge[4] = {0, page_w, page_h, 0};  // top y, right x, bottom y, left x
  const double crop_edge[4] = {r.crop_y0, r.crop_x1, r.crop_y1, r.crop_x0};
  int real = 0;
  for (int i = 0; i < 4; ++i) {
    real += r.sides[i].real;
    EXPECT_EQ(r.sides[i].used, r.sides[i].real) << kSideNames[i] << " " << r.sides[i].note;
    // A real side bounds the crop where the page edge is (to a pixel).
    if (r.sides[i].used) {
      EXPECT_LT(std::abs(crop_edge[i] - true_edge[i]), 1.5 / r.pixels_per_unit) << kSideNames[i];
    }
  }
  const double aspect = double(r.rectified.cols) / r.rectified.rows;
  if (real == 4) {
    EXPECT_EQ(r.crop_rule, "boundary-lines");
    EXPECT_NEAR(aspect / (gt->width_m / gt->height_m), 1.0, 0.01);
  } else {
    EXPECT_EQ(r.crop_rule, "real-sides-and-visible-mesh");
    // Not beyond the page on the cut-off sides either.
    EXPECT_GT(r.crop_x0, -0.01 * diag);
    EXPECT_LT(r.crop_x1, page_w + 0.01 * diag);
  }
  EXPECT_LT(std::abs(r.rotation_deg), 0.05);

  // Content: flat.png seen through the crop agrees with the rendering.
  const cv::Mat flat = cv::imread((set / "ground_truth/flat.png").string());
  ASSERT_FALSE(flat.empty());
  const cv::Mat expected = FlatInRenderFrame(flat, page_w / flat.cols, r);
  cv::Mat1b inside;
  cv::threshold(FlatInRenderFrame(cv::Mat1b(flat.size(), 255), page_w / flat.cols, r), inside, 254,
                255, cv::THRESH_BINARY);
  cv::Mat1b mask = r.page_mask & inside;
  cv::erode(mask, mask, cv::Mat(), cv::Point(-1, -1), 3);
  ASSERT_GT(cv::countNonZero(mask), 0.2 * mask.total());
  const cv::Mat1f a = Detail(expected), b = Detail(r.rectified);
  const double ncc = Correlation(a, b, mask);
  cv::Mat1f shifted;
  cv::warpAffine(b, shifted, cv::Matx23d(1, 0, 3, 0, 1, 3), b.size());
  const double ncc_shifted = Correlation(a, shifted, mask);
  const TileOffsets off = FindTileOffsets(a, b, mask, 48, 8);
  double total_s = 0;
  for (const auto& step : r.timings) total_s += step.second;
  std::printf(
      "%s: %dx%d (%.1f px/unit, ref %.1f) aspect %.4f true %.4f crop %s | ncc "
      "%.3f "
      "(shifted 3px %.3f) | tiles %d matched %d offset median %.2f p90 %.2f "
      "max %.2f px "
      "| hidden %.3f | %.2f s\n",
      set.filename().c_str(), r.rectified.cols, r.rectified.rows, r.pixels_per_unit,
      r.reference_pixels_per_unit, aspect, gt->width_m / gt->height_m, r.crop_rule.c_str(), ncc,
      ncc_shifted, off.tiles, off.matched, off.median, off.p90, off.max, r.hidden_fraction,
      total_s);
  if (std::getenv("DOCUNFOLD_KEEP_TEST_DIRS")) {
    cv::imwrite("/tmp/render-" + set.filename().string() + ".png", r.rectified);
    cv::imwrite("/tmp/render-expected-" + set.filename().string() + ".png", expected);
  }
  EXPECT_GT(ncc, 0.5);
  EXPECT_GT(ncc, ncc_shifted + 0.25);
  ASSERT_GT(off.tiles, 10);
  EXPECT_GE(off.matched, 0.8 * off.tiles);
  EXPECT_LE(off.median, 0.75);
  EXPECT_LE(off.p90, 1.5);
}

std::string SetName(const ::testing::TestParamInfo<fs::path>& info) {
  std::string name = info.param.filename().string();
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(DataSets, RenderTruth, ::testing::ValuesIn(RenderDataSets()), SetName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(RenderTruth);

}  // namespace
}  // namespace docunfold::testing
