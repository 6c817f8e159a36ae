#include "stages/report/report.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <string>

#include "common/atomic_file.h"
#include "common/json_io.h"
#include "tests/support/test_support.h"

namespace docunfold::report {
namespace {

using testing::TempDir;

// render's warnings (render.json "warnings") stand above the result, escaped.
TEST(ReportRun, ShowsRendersWarningsAboveTheResult) {
  TempDir dir;
  EnsureDirectory(dir / "data" / "images");
  EnsureDirectory(dir / "work" / "60_render");
  WriteImageAtomic(dir / "work" / "60_render" / "rectified.png",
                   cv::Mat3b(30, 40, cv::Vec3b(200, 200, 200)));
  ReportOptions o;
  o.data = dir / "data";
  o.work = dir / "work";
  o.out = dir / "work" / "report.html";
  const std::string shown = "<p class=\"warning\">render: M is &lt;off&gt; along its top side</p>";

  WriteJsonAtomic(o.work / "60_render" / "render.json", Json{{"warnings", Json::array()}});
  EXPECT_EQ(report::Run(o).html.find("class=\"warning\""), std::string::npos);

  WriteJsonAtomic(o.work / "60_render" / "render.json",
                  Json{{"warnings", {"M is <off> along its top side"}}});
  const std::string html = report::Run(o).html;
  const size_t warning = html.find(shown);
  ASSERT_NE(warning, std::string::npos);
  EXPECT_LT(warning, html.find("60_render/rectified.png ("));
}

}  // namespace
}  // namespace docunfold::report
