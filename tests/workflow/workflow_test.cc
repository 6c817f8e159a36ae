// The Snakemake workflow (workflow/Snakefile) on a real single-node Slurm
// cluster started for the test: a sample's photos in a plain folder and a data
// set with a broken photo submitted through the Slurm profile, each data set
// one Slurm job.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/json_io.h"
#include "tests/support/test_support.h"
#include "tests/workflow/slurm_cluster.h"

namespace docunfold::testing {
namespace {

// A data set whose second photo was cut short: one photo is left, too few.
fs::path BrokenDataSet(const fs::path& dir) {
  const fs::path images = dir / "broken/images";
  fs::create_directories(images);
  int n = 0;
  for (const auto& e : fs::directory_iterator(SampleDir("set07") / "images")) {
    if (n == 2) break;
    fs::copy_file(e.path(), images / e.path().filename());
    if (n++ == 1) fs::resize_file(images / e.path().filename(), 4000);
  }
  return dir / "broken";
}

TEST(Workflow, SlurmRunsEachDataSetAsAJob) {
  TempDir dir;
  SlurmCluster cluster(dir / "slurm");
  if (!cluster.skip_reason().empty()) GTEST_SKIP() << cluster.skip_reason();
  if (RunCommand("command -v snakemake > /dev/null").exit_code != 0)
    GTEST_SKIP() << "snakemake is missing (Debian: snakemake)";

  // A sample's photos only, in a plain folder as a phone exports them (no
  // images/; no ground truth: no evaluate, a shorter run), so its result must
  // equal the e2e run's of the same photos. One sample: each more is another
  // whole pipeline run in CI's half hour.
  const std::vector<std::string> samples = {"set07"};
  std::string sets;
  for (const std::string& s : samples) {
    fs::create_directories(dir / "sets" / s);
    fs::copy(SampleDir(s) / "images", dir / "sets" / s);
    sets += (dir / "sets" / s).string() + ",";
  }
  sets += BrokenDataSet(dir / "sets").string();
  const fs::path work = dir / "work";
  // From a folder of its own (Snakemake keeps its state and lock there); one
  // CPU per job, so that two run side by side on the 2-CPU node.
  fs::create_directories(dir / "run");
  const std::string snakemake =
      "cd " + Quote((dir / "run").string()) + " && " + cluster.Environment() +
      " snakemake --snakefile " + Quote((SourceDir() / "workflow/Snakefile").string()) +
      " --profile " + Quote((SourceDir() / "workflow/profiles/slurm").string()) +
      " --set-threads dataset=1 --config sets=" + Quote(sets) +
      " work_root=" + Quote(work.string()) +
      " build=" + Quote(StageBinary("sfm").parent_path().parent_path().string());
  const CommandResult run = RunCommand(snakemake + " 2>&1");
  // keep-going: the broken data set fails the run, the others complete.
  EXPECT_NE(run.exit_code, 0) << run.output;

  for (const std::string& s : samples) {
    SCOPED_TRACE(s);
    const fs::path row_file = work / "batch/rows" / (s + ".json");
    ASSERT_TRUE(fs::is_regular_file(row_file)) << run.output;
    const Json row = ReadJsonFile(row_file);
    EXPECT_EQ(row["status"], "ok");
    // It ran under Slurm: the job's environment had its job id.
    EXPECT_FALSE(row["slurm_job_id"].get<std::string>().empty());
    const cv::Mat batch = cv::imread((work / s / "60_render/rectified.png").string());
    const cv::Mat made = cv::imread((E2eDir() / "work" / s / "60_render/rectified.png").string());
    ASSERT_FALSE(batch.empty());
    ASSERT_EQ(batch.size(), made.size());
    EXPECT_EQ(cv::norm(batch, made, cv::NORM_INF), 0);
    EXPECT_TRUE(fs::is_regular_file(work / s / "80_pdf" / (s + ".pdf")));
  }
  const Json broken = ReadJsonFile(work / "batch/rows/broken.failed.json");
  EXPECT_EQ(broken["status"], "failed");
  EXPECT_EQ(broken["failed_stage"], "sfm");
  EXPECT_NE(broken["message"].get<std::string>().find("photo"), std::string::npos)
      << broken["message"];

  const std::string summary = ReadFileText(work / "batch/summary.csv");
  for (const std::string& s : samples)
    EXPECT_NE(summary.find("\n" + s + ",ok,"), std::string::npos);
  EXPECT_NE(summary.find("\nbroken,failed,sfm,"), std::string::npos) << summary;
  EXPECT_NE(ReadFileText(work / "batch/index.html").find("failed in <b>sfm</b>"),
            std::string::npos);

  // A rerun does only what failed.
  const CommandResult again = RunCommand(snakemake + " -n 2>&1");
  size_t jobs = 0;
  for (size_t at = again.output.find("rule dataset:"); at != std::string::npos;
       at = again.output.find("rule dataset:", at + 1))
    ++jobs;
  EXPECT_EQ(jobs, 1u) << again.output;
  EXPECT_NE(again.output.find("broken"), std::string::npos) << again.output;
}

}  // namespace
}  // namespace docunfold::testing
