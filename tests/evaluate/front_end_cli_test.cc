// evaluate --front-end as the benchmark runs it: a front end made from the
// ground truth (a perfect sfm, segment-boundary and detector) scores
// perfectly; a detector a few pixels off, a mask that misses part of the
// page and sides wrongly flagged are caught; bad input gets the documented
// exit codes and nothing written.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/json_io.h"
#include "tests/evaluate/truth_frontend.h"
#include "tests/optimize/truth_features.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

class FrontEndCli : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    data = SampleDir(GetParam());
    if (!fs::is_regular_file(data / "ground_truth/mesh.ply")) GTEST_SKIP() << "no " << data;
    auto loaded = LoadGroundTruth(data);
    ASSERT_TRUE(loaded);
    gt = std::move(*loaded);
    reference = WriteTruthFrontEnd(gt, work);
    fs::create_directories(work / "30_features");
    WriteJsonAtomic(work / "30_features/features.json", TruthFeatures(gt, reference));
  }
  CommandResult Run(const std::string& extra = "") const {
    return RunCommand(Quote(StageBinary("evaluate").string()) + " --front-end --data " +
                      Quote(data.string()) + " --work " + Quote(work.string()) + " --out " +
                      Quote(out.string()) + " " + extra);
  }
  TempDir dir;
  fs::path data, work = dir / "work", out = dir / "work/70_eval/front_end.json";
  GroundTruth gt;
  std::string reference;
};

TEST_P(FrontEndCli, TheTruthScoresPerfectlyAndDefectsAreCaught) {
  CommandResult r = Run();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("front end in " + reference), std::string::npos) << r.output;
  Json doc = ReadJsonFile(out);
  EXPECT_EQ(doc["format"], "docunfold.front-end-metrics");
  EXPECT_EQ(RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                       Quote(out.string()))
                .exit_code,
            0);
  const Json& b = doc["boundary"];
  EXPECT_GE(b["iou"].get<double>(), 0.99);
  EXPECT_LE(b["worst_corner_fraction"].get<double>(), 0.002);
  EXPECT_TRUE(b["holds"]["iou"].get<bool>() && b["holds"]["corners"].get<bool>() &&
              b["holds"]["cut_flags"].get<bool>())
      << b.dump();
  // The truth front end marks a cut side wholly not real (no real parts), so
  // the true outline is covered only where the page is whole.
  if (!b["page_cut"].get<bool>()) {
    EXPECT_TRUE(b["holds"]["sides"].get<bool>()) << b.dump();
  }
  const Json& f = doc["features"];
  EXPECT_GE(f["precision"].get<double>(), 0.99);
  EXPECT_GE(f["recall"].get<double>(), 0.85);
  EXPECT_TRUE(f["recall_required"].get<bool>());  // set01: text, set08: text cut off

  // Segments 4 px off their lines, across them: none within 2 px, and so
  // none covers one.
  Json shifted = ReadJsonFile(work / "30_features/features.json");
  for (Json& s : shifted["segments"]) {
    Json& points = s["points"];
    const double dx = points.back()[0].get<double>() - points.front()[0].get<double>();
    const double dy = points.back()[1].get<double>() - points.front()[1].get<double>();
    const double length = std::hypot(dx, dy);
    for (Json& p : points) {
      p[0] = p[0].get<double>() - 4.0 * dy / length;
      p[1] = p[1].get<double>() + 4.0 * dx / length;
    }
  }
  WriteJsonAtomic(work / "30_features/features.json", shifted);
  // A mask that misses the page's left third, and every side flagged cut.
  cv::Mat1b mask = cv::imread((work / "20_boundary/mask.png").string(), cv::IMREAD_GRAYSCALE);
  const cv::Rect page = cv::boundingRect(mask);
  mask(cv::Rect(page.x, page.y, page.width / 3, page.height)).setTo(0);
  cv::imwrite((work / "20_boundary/mask.png").string(), mask);
  Json boundary = ReadJsonFile(work / "20_boundary/boundary.json");
  for (auto& [name, side] : boundary["sides"].items()) side["real"] = false;
  WriteJsonAtomic(work / "20_boundary/boundary.json", boundary);
  r = Run();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  doc = ReadJsonFile(out);
  EXPECT_LT(doc["boundary"]["iou"].get<double>(), 0.8);
  EXPECT_FALSE(doc["boundary"]["holds"]["iou"].get<bool>());
  EXPECT_EQ(doc["boundary"]["holds"]["cut_flags"].get<bool>(),
            doc["boundary"]["page_cut"].get<bool>());  // all flagged cut: right only if it is
  EXPECT_LT(doc["features"]["precision"].get<double>(), 0.2);
  EXPECT_LT(doc["features"]["recall"].get<double>(), 0.2);
  EXPECT_FALSE(doc["features"]["holds"]["precision"].get<bool>());
}

INSTANTIATE_TEST_SUITE_P(Samples, FrontEndCli, ::testing::Values("set01", "set08"));

TEST(FrontEndCliErrors, BadInputAndUsage) {
  TempDir dir;
  const fs::path data = SampleDir("set01"), out = dir / "fe.json";
  if (!fs::is_regular_file(data / "ground_truth/mesh.ply")) GTEST_SKIP() << "no " << data;
  const std::string evaluate = Quote(StageBinary("evaluate").string());
  // No 10_sfm/cameras.json in the work directory.
  CommandResult r =
      RunCommand(evaluate + " --front-end --data " + Quote(data.string()) + " --work " +
                 Quote((dir / "work").string()) + " --out " + Quote(out.string()));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("10_sfm/cameras.json: no such file"), std::string::npos) << r.output;
  // --result belongs to the image metrics; --front-end needs --work.
  r = RunCommand(evaluate + " --front-end --result x.png --data " + Quote(data.string()) +
                 " --work " + Quote(dir.path().string()) + " --out " + Quote(out.string()));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = RunCommand(evaluate + " --front-end --data " + Quote(data.string()) + " --out " +
                 Quote(out.string()));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // A data set without a true surface: a note, nothing written.
  fs::create_directories(dir / "plain/images");
  r = RunCommand(evaluate + " --front-end --data " + Quote((dir / "plain").string()) + " --work " +
                 Quote(dir.path().string()) + " --out " + Quote(out.string()));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no true surface"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace docunfold::testing
