#include "stages/report/stage_outputs.h"

#include <gtest/gtest.h>

#include <string>

#include "common/errors.h"

namespace docunfold::report {
namespace {

const Json kRender = Json::parse(R"({
  "inputs": {"meshes": "work/set01/50_optimize"}, "rotation_deg": 0,
  "pixels_per_unit": 60, "crop": {"x0": 0, "y0": 0}})");

// Whether DrawFeatureLines drew anything in this row or column of the image.
bool Drawn(const cv::Mat& out_part, const cv::Mat& rectified_part) {
  return cv::norm(out_part, rectified_part, cv::NORM_L1) > 0;
}

TEST(DrawFeatureLines, DrawsOptimizesLines) {
  const cv::Mat rectified(48, 64, CV_8UC3, cv::Scalar(255, 255, 255));
  const Json lines =
      Json::parse(R"({"lines": [{"kind": "text", "flat": [[0.1, 0.2], [0.9, 0.2]]}]})");
  const cv::Mat out = DrawFeatureLines(rectified, kRender, lines);
  ASSERT_EQ(out.size(), rectified.size());
  EXPECT_NE(cv::norm(out, rectified, cv::NORM_L1), 0);
  EXPECT_EQ(LinesNote(lines), "Feature lines straightened in M': 1 text (50_optimize/lines.json).");
}

// render warped M' so that its slanted right side is the crop's edge: a line
// along that side is drawn along the image's edge column, not slanted.
TEST(DrawFeatureLines, FollowsRendersWarpOntoTheSides) {
  const cv::Mat rectified(48, 64, CV_8UC3, cv::Scalar(255, 255, 255));
  const Json render = Json::parse(R"({
    "inputs": {"meshes": "work/set01/50_optimize"}, "rotation_deg": 0, "pixels_per_unit": 60,
    "crop": {"x0": 0, "y0": 0, "warp_box": [0, 0, 1, 0.8]},
    "sides": {"right": {"warped": true, "point": [1.05, 0.4], "direction": [-0.05, 1]}}})");
  // On the right side's line: x = 1.065 at y = 0.1, 1.035 at y = 0.7.
  const Json lines =
      Json::parse(R"({"lines": [{"kind": "edge", "flat": [[1.065, 0.1], [1.035, 0.7]]}]})");
  const cv::Mat out = DrawFeatureLines(rectified, render, lines);
  auto drawn_in_column = [&](int col) { return Drawn(out.col(col), rectified.col(col)); };
  EXPECT_TRUE(drawn_in_column(59) || drawn_in_column(60));
  EXPECT_FALSE(drawn_in_column(63));  // where the line's top end is without the warp
}

// render gives each axis its own scale (the crop kept whole): a line across
// the page at y = 0.9 of M' lies on row 0.9 * 40 - 0.5, not 0.9 * 60 - 0.5
// (past the image's 48 rows).
TEST(DrawFeatureLines, TakesTheScaleDownTheRowsFromPixelsPerUnitY) {
  const cv::Mat rectified(48, 64, CV_8UC3, cv::Scalar(255, 255, 255));
  Json render = kRender;
  render["pixels_per_unit_y"] = 40;
  const Json lines =
      Json::parse(R"({"lines": [{"kind": "text", "flat": [[0.1, 0.9], [0.9, 0.9]]}]})");
  const cv::Mat out = DrawFeatureLines(rectified, render, lines);
  auto drawn_in_row = [&](int row) { return Drawn(out.row(row), rectified.row(row)); };
  EXPECT_TRUE(drawn_in_row(35) || drawn_in_row(36));
  EXPECT_FALSE(drawn_in_row(20));
}

// The fuzzer's input (fuzz/lines_fuzzer.cc): a point of a line that is not
// [x, y] was read past the end of its array.
TEST(DrawFeatureLines, RejectsAPointThatIsNotXY) {
  const cv::Mat rectified(48, 64, CV_8UC3, cv::Scalar(255, 255, 255));
  for (const char* point : {"[]", "[0.5]", "[0.5, \"a\"]", "{}"}) {
    const Json lines = Json::parse(std::string(R"({"lines": [{"kind": "text", "flat": [[0, 0], )") +
                                   point + "]}]}");
    try {
      DrawFeatureLines(rectified, kRender, lines);
      ADD_FAILURE() << point << ": drawn without error";
    } catch (const InputError& e) {
      EXPECT_STREQ(e.what(), "50_optimize/lines.json:/lines/0/flat/1: expected [x, y]");
    }
  }
  EXPECT_THROW(DrawFeatureLines(rectified, kRender, Json::parse(R"({"lines": {"a": 1}})")),
               InputError);
}

// Numbers too large for an int (the fuzzers' render.json and points.json)
// were converted to one: undefined behaviour.
TEST(DrawFeatureLines, RejectsQuarterTurnsThatAreNotAnInteger) {
  const cv::Mat rectified(48, 64, CV_8UC3, cv::Scalar(255, 255, 255));
  const Json lines =
      Json::parse(R"({"lines": [{"kind": "text", "flat": [[0.1, 0.2], [0.9, 0.2]]}]})");
  Json render = kRender;
  render["orientation"]["quarter_turns_clockwise"] = 1e300;
  try {
    DrawFeatureLines(rectified, render, lines);
    ADD_FAILURE() << "drawn without error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "60_render/render.json:/orientation/quarter_turns_clockwise: expected an integer");
  }
  render["orientation"]["quarter_turns_clockwise"] = -7;  // three turns
  EXPECT_EQ(DrawFeatureLines(rectified, render, lines).size(), cv::Size(64, 48));
}

TEST(PointsCounts, RejectsCountsThatAreNotIntegers) {
  EXPECT_EQ(PointsCounts(Json::parse(R"({"points": {"sfm_in_region": 3, "texture": 4}})")),
            " 3 sfm points on the page, 4 texture, 0 outline, 0 shading-step, 0 swept.");
  try {
    PointsCounts(Json::parse(R"({"points": {"texture": 1e300}})"));
    ADD_FAILURE() << "counted without error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "25_points/points.json:/points/texture: expected an integer");
  }
}

TEST(PdfCheckSummary, SaysWhatASearchFindsAndTheSizes) {
  const Json metrics = Json::parse(R"({"format": "docunfold.pdf-metrics",
    "text": {"words_found": 0.8378, "cer_reading_order": 0.329},
    "page": {"width_mm": 130.5, "height_mm": 194.9, "true_width_mm": 100, "true_height_mm": 150}})");
  EXPECT_EQ(PdfCheckSummary(metrics),
            "Read back against the true text: a search finds 83.8 % of its words, and copied "
            "text has a CER of 0.329; the page is 130 × 195 mm, the true page 100 × 150 mm.");
  EXPECT_EQ(PdfCheckSummary(Json::parse(R"({"format": "docunfold.pdf"})")), "");
  EXPECT_EQ(PdfCheckSummary(Json()), "");
}

}  // namespace
}  // namespace docunfold::report
