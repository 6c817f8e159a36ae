// scripts/bench_report.py turns the files scripts/bench.sh leaves in the work
// directories into bench/results.json (valid against its schema) and a
// readable bench/results.md.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <utility>
#include <vector>

#include "common/json_io.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

std::string ReadAll(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(BenchReport, WritesValidJsonAndAReadableTable) {
  TempDir dir;
  const fs::path data = dir / "data" / "setA";
  fs::create_directories(data / "images");
  fs::create_directories(data / "ground_truth");
  cv::imwrite((data / "images" / "view_00.jpg").string(), cv::Mat3b(48, 64, cv::Vec3b(1, 2, 3)));
  cv::imwrite((data / "images" / "view_01.png").string(), cv::Mat3b(48, 64, cv::Vec3b(1, 2, 3)));
  cv::imwrite((data / "ground_truth" / "flat.png").string(), cv::Mat3b(8, 8));
  const fs::path work = dir / "work" / "setA";
  fs::create_directories(work / "bench");
  fs::create_directories(work / "70_eval");
  std::ofstream(work / "timings.jsonl")
      << R"({"stage": "truth-frontend", "seconds": 1.50, "max_rss_mb": 200.0, "exit": 0})"
         "\n"
      << R"({"stage": "init-mesh", "seconds": 3.25, "max_rss_mb": 100.5, "exit": 0})"
         "\n"
      << R"({"stage": "render", "seconds": 2.00, "max_rss_mb": 90.0, "exit": 1})"
         "\n";
  std::ofstream(work / "bench" / "timings.jsonl")
      << R"({"stage": "make:homography", "seconds": 0.50, "max_rss_mb": 60.0, "exit": 0})"
         "\n"
      << R"({"stage": "evaluate:homography", "seconds": 7.00, "max_rss_mb": 130.0, "exit": 0})"
         "\n"
      << R"({"stage": "make:oracle", "seconds": 0.70, "max_rss_mb": 110.0, "exit": 0})"
         "\n"
      << R"({"stage": "evaluate:oracle", "seconds": 6.00, "max_rss_mb": 120.0, "exit": 0})"
         "\n";
  std::ofstream(work / "bench" / "pipeline.exit") << "2\n";
  Json metrics = {{"format", "docunfold.metrics"},
                  {"metrics",
                   {{"ms_ssim", 0.5},
                    {"ld", 10.0},
                    {"li_d", 2.0},
                    {"cer", 0.25},
                    {"wer", nullptr},
                    {"surface_mean_pct", nullptr}}}};
  std::ofstream(work / "70_eval" / "metrics-homography.json") << metrics.dump();
  metrics["metrics"]["ms_ssim"] = 0.9;
  metrics["metrics"]["cer"] = 0.05;
  std::ofstream(work / "70_eval" / "metrics-oracle.json") << metrics.dump();
  std::ofstream(work / "bench" / "rows.tsv")
      << "docunfold-init\tskipped\t\t\t\tno render binary\n"
      << "oracle\tok\t" << (work / "bench" / "oracle.png").string() << "\t"
      << (work / "70_eval" / "metrics-oracle.json").string() << "\t\t\n"
      << "homography\tok\t" << (work / "bench" / "homography.png").string() << "\t"
      << (work / "70_eval" / "metrics-homography.json").string() << "\t\t\n"
      << "docunfold\tfailed\t\t\t\tevaluate failed: boom\n";

  // The two solvers' logs (optimize log.json, only what the report reads):
  // L-BFGS ends higher, so F* is its final F; Gauss-Newton reached it at 2 s.
  auto solver_log = [](double seconds, std::vector<std::pair<double, double>> last) {
    Json its = Json::array();
    for (const auto& [t, f] : last) its.push_back({{"seconds", t}, {"F", f}});
    return Json{{"seconds", seconds},
                {"rounds",
                 {{{"iterations", {{{"seconds", 0.5}, {"F", 9.0}}}}, {"solver", {{"method", "x"}}}},
                  {{"iterations", its}, {"solver", {{"method", "y"}}}}}}};
  };
  fs::create_directories(work / "bench" / "solver_gn");
  fs::create_directories(work / "bench" / "solver_lbfgs");
  std::ofstream(work / "bench" / "solver_gn" / "log.json")
      << solver_log(3, {{1, 5.0}, {2, 3.9}, {3, 3.5}}).dump();
  std::ofstream(work / "bench" / "solver_lbfgs" / "log.json")
      << solver_log(20, {{5, 6.0}, {20, 4.0}}).dump();

  const fs::path out = dir / "out";
  CommandResult r = RunCommand(
      "/usr/bin/python3 " + Quote((SourceDir() / "scripts" / "bench_report.py").string()) +
      " --root " + Quote(SourceDir().string()) + " --work " + Quote((dir / "work").string()) +
      " --out " + Quote(out.string()) +
      " --frontend truth --eval-flags=--ocr-at-truth-size --solver-set setA setA=" +
      Quote(data.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;

  CommandResult v = RunCommand(Quote((SourceDir() / "scripts" / "validate-json").string()) + " " +
                               Quote((out / "results.json").string()));
  EXPECT_EQ(v.exit_code, 0) << v.output;
  const Json j = Json::parse(ReadAll(out / "results.json"));
  ASSERT_EQ(j["sets"].size(), 1u);
  EXPECT_EQ(j["sets"][0]["views"], 2);
  EXPECT_EQ(j["sets"][0]["image_size"], "64x48");
  EXPECT_EQ(j["sets"][0]["pipeline"]["failed_stage"], "render");
  // Rows in the fixed order: homography, oracle, docunfold, docunfold-init.
  EXPECT_EQ(j["sets"][0]["rows"][0]["method"], "homography");
  EXPECT_EQ(j["sets"][0]["rows"][0]["evaluate"]["seconds"], 7.0);
  EXPECT_EQ(j["sets"][0]["rows"][1]["method"], "oracle");
  EXPECT_EQ(j["summary"][1]["means"]["ms_ssim"], 0.9);

  const std::string md = ReadAll(out / "results.md");
  EXPECT_NE(md.find("| setA | homography | 0.5000 | 10.00 | 2.00 | 0.2500 | – |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| setA | docunfold | failed: evaluate failed: boom |"), std::string::npos)
      << md;
  EXPECT_NE(md.find("| truth-frontend | init-mesh | render |"), std::string::npos) << md;
  EXPECT_NE(md.find("| setA | 2 × 64x48 | 1.5 / 200 | 3.2 / 100 | 2.0 / 90 (exit 1) | 6.8 |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("Summary: homography MS-SSIM 0.5000"), std::string::npos) << md;
  EXPECT_NE(md.find("docunfold-init: no render binary (setA)"), std::string::npos) << md;
  EXPECT_NE(md.find("Front end: **ground truth**"), std::string::npos) << md;
  EXPECT_NE(md.find("on the result resized to flat.png's size"), std::string::npos) << md;
  EXPECT_EQ(j["producer"]["options"]["eval_flags"], "--ocr-at-truth-size");
  // Solvers: F* = 4 (the worse final F); GN reached it at 2 s, L-BFGS at 20 s.
  EXPECT_EQ(j["solvers"]["target_F"], 4.0);
  EXPECT_EQ(j["solvers"]["solvers"][0]["seconds_to_target"], 2.0);
  EXPECT_EQ(j["solvers"]["solvers"][1]["seconds_to_target"], 20.0);
  EXPECT_EQ(j["solvers"]["solvers"][0]["iterations"], 4);
  EXPECT_NE(md.find("| gn | y | 3.0 | 4 | 3.5 | 2.0 | 9, 3.5 |"), std::string::npos) << md;
}

}  // namespace
}  // namespace docunfold::testing
