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

// A folder of photos as pipeline.mk passes it (WORK/.photos/images a link to
// it): the report is named after that folder, and the photos count only what
// was read as a photo: a note and a folder sfm left out are listed, not
// counted.
TEST(ReportRun, NamedAfterThePhotosFolderCountsThePhotosAndListsWhatWasLeftOut) {
  TempDir dir;
  const fs::path folder = dir / "Letter 2";
  ReportOptions o;
  o.work = dir / "work";
  o.data = o.work / ".photos";
  o.out = dir / "work" / "report.html";
  EnsureDirectory(folder / "Edited");
  EnsureDirectory(o.data);
  fs::create_directory_symlink(folder, o.data / "images");
  // a.png and c.png registered; b.png, a copy of a.png, left out; z.png of
  // another page, not given to the mapper.
  for (const char* name : {"a.png", "b.png", "c.png", "z.png"})
    WriteImageAtomic(folder / name, cv::Mat3b(30, 40, cv::Vec3b(90, 120, 200)));
  WriteTextAtomic(folder / "note.txt", "not a photo");
  EnsureDirectory(o.work / "10_sfm");
  WriteJsonAtomic(o.work / "10_sfm" / "cameras.json",
                  Json{{"reference", "a.png"},
                       {"views", {{{"image", "a.png"}}, {{"image", "c.png"}}}},
                       {"left_out",
                        {{{"image", "Edited/"}, {"reason", "a folder: its photos are not read"}},
                         {{"image", "b.png"}, {"reason", "the same photo as a.png"}},
                         {{"image", "note.txt"}, {"reason", "not a photo"}}}},
                       {"colmap", {{"unregistered", {"z.png"}}, {"not_mapped", {"z.png"}}}}});
  const std::string html = report::Run(o).html;
  EXPECT_NE(html.find("<title>docunfold report: Letter 2</title>"), std::string::npos);
  EXPECT_NE(html.find("Photos from <code>" + fs::canonical(folder).string() + "</code> (5 files)"),
            std::string::npos);
  EXPECT_NE(html.find("2 of 3 photos registered."), std::string::npos) << html;
  EXPECT_NE(html.find("<li>Edited/ (a folder: its photos are not read)</li>"), std::string::npos);
  EXPECT_NE(html.find("<li>note.txt (not a photo)</li>"), std::string::npos);
  EXPECT_NE(html.find("<li>b.png (the same photo as a.png)</li>"), std::string::npos);
  EXPECT_EQ(html.find("b.png — "), std::string::npos);  // no thumbnail of the copy
  EXPECT_NE(html.find("z.png — not registered (no features in common with the registered ones"),
            std::string::npos);
}

// The stages' table has a row for each stage that ran, the pdf stage's too,
// with its flags, and their total.
TEST(ReportRun, StagesTableTimesEveryStageThatRan) {
  TempDir dir;
  ReportOptions o;
  o.data = dir / "data";
  o.work = dir / "work";
  o.out = dir / "work" / "report.html";
  EnsureDirectory(o.data / "images");
  EnsureDirectory(o.work / ".flags");
  WriteTextAtomic(o.work / "timings.jsonl",
                  "{\"stage\": \"sfm\", \"seconds\": 10.0, \"max_rss_mb\": 1000.0, \"exit\": 0}\n"
                  "{\"stage\": \"pdf\", \"seconds\": 2.5, \"max_rss_mb\": 150.0, \"exit\": 0}\n");
  WriteTextAtomic(o.work / ".flags" / "pdf", "--lang deu\n");
  const std::string html = report::Run(o).html;
  EXPECT_NE(html.find("<tr><td class=l>pdf</td><td>2.5</td><td>150</td><td class=l><code>--lang "
                      "deu</code></td></tr>"),
            std::string::npos)
      << html;
  EXPECT_NE(html.find("<th class=l>total</th><th>12.5</th>"), std::string::npos);
}

}  // namespace
}  // namespace docunfold::report
