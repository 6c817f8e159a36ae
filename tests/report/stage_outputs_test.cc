#include "stages/report/stage_outputs.h"

#include <gtest/gtest.h>

#include <string>

#include "common/errors.h"

namespace docunfold::report {
namespace {

const Json kRender = Json::parse(R"({
  "inputs": {"meshes": "work/set01/50_optimize"}, "rotation_deg": 0,
  "pixels_per_unit": 60, "crop": {"x0": 0, "y0": 0}})");

TEST(DrawFeatureLines, DrawsOptimizesLines) {
  const cv::Mat rectified(48, 64, CV_8UC3, cv::Scalar(255, 255, 255));
  const Json lines =
      Json::parse(R"({"lines": [{"kind": "text", "flat": [[0.1, 0.2], [0.9, 0.2]]}]})");
  const cv::Mat out = DrawFeatureLines(rectified, kRender, lines);
  ASSERT_EQ(out.size(), rectified.size());
  EXPECT_NE(cv::norm(out, rectified, cv::NORM_L1), 0);
  EXPECT_EQ(LinesNote(lines), "Feature lines straightened in M': 1 text (50_optimize/lines.json).");
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

}  // namespace
}  // namespace docunfold::report
