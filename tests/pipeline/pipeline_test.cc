// pipeline.mk end to end on a small sample: outputs exist and validate, a
// second run does nothing, changing a stage's flags reruns exactly that stage
// and what follows, and FEATURES= substitutes another detector's file.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/json_io.h"
#include "tests/support/ground_truth.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

const char* kSample = "set01";

// Each case works on its own copy of the e2e run's work directory of the
// sample (timestamps kept), so make sees a finished pipeline.
class Pipeline : public ::testing::Test {
 protected:
  fs::path Work() const { return dir_.path() / "work"; }
  CommandResult Make(const std::string& args) const {
    return RunCommand(
        "make --no-print-directory -f " + Quote((SourceDir() / "pipeline.mk").string()) +
        " DATA=" + kSample + " WORK=" + Quote(Work().string()) + " NO_BUILD=1" +
        " BUILD=" + Quote(fs::path(DOCUNFOLD_BIN_DIR).parent_path().string()) + " " + args);
  }
  // Makes render, optimize in one round: these cases are about what make
  // reruns and which files it reads, not about the result, and optimize's
  // full schedule would be most of their time.
  CommandResult MakeRender(const std::string& args) const {
    return Make("render OPTIMIZE_FLAGS='--rounds 1' " + args);
  }
  fs::file_time_type MTime(const std::string& rel) const {
    return fs::last_write_time(Work() / rel);
  }
  void SetUp() override {
    if (!fs::is_directory(SampleDir(kSample))) GTEST_SKIP() << "no sample " << kSample;
    const fs::path e2e = E2eDir() / "work" / kSample;
    ASSERT_TRUE(fs::is_directory(e2e)) << e2e << " (did the e2e_run fixture run?)";
    CommandResult copy = RunCommand("cp -a " + Quote(e2e.string()) + " " + Quote(Work().string()));
    ASSERT_EQ(copy.exit_code, 0) << copy.output;
    // The first make adds what the benchmark run does not make (evaluate's
    // metrics.json and the report) and reruns nothing else.
    first_ = Make("all EVAL_FLAGS=--no-ocr");
    ASSERT_EQ(first_.exit_code, 0) << first_.output;
  }
  TempDir dir_;
  CommandResult first_;
};

TEST_F(Pipeline, WritesEveryStageOutputAndTheyValidate) {
  for (const char* stage : {"bin/sfm", "bin/segment-boundary", "bin/densify", "bin/detect-features",
                            "bin/init-mesh", "bin/optimize", "bin/render"})
    EXPECT_EQ(first_.output.find(stage), std::string::npos) << first_.output;
  for (const char* f :
       {"10_sfm/cameras.json", "10_sfm/points.ply", "10_sfm/reference.png",
        "20_boundary/boundary.json", "20_boundary/mask.png", "20_boundary/overlay.png",
        "25_points/points.ply", "25_points/points.json", "25_points/overlay.png",
        "30_features/features.json", "30_features/overlay.png", "40_init/mesh3d.ply",
        "50_optimize/log.json", "50_optimize/scene.glb", "60_render/rectified.png",
        "70_eval/metrics.json", "70_eval/pdf.json", "report.html"})
    EXPECT_TRUE(fs::is_regular_file(Work() / f)) << f;
  for (const auto& e : fs::recursive_directory_iterator(Work())) {
    if (e.path().extension() != ".json" || e.path().string().find("/colmap/") != std::string::npos)
      continue;
    CommandResult r = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                                 Quote(e.path().string()));
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
  // No temporary files are left behind by atomic writes.
  for (const auto& e : fs::recursive_directory_iterator(Work()))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
}

TEST_F(Pipeline, SecondRunDoesNothingAndFlagsRerunOnlyDownstream) {
  const auto sfm_time = MTime("10_sfm/cameras.json");
  const auto boundary_time = MTime("20_boundary/boundary.json");
  CommandResult again = Make("all EVAL_FLAGS=--no-ocr");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(again.output.find("bin/sfm"), std::string::npos) << again.output;
  EXPECT_EQ(again.output.find("bin/segment-boundary"), std::string::npos) << again.output;
  EXPECT_EQ(MTime("10_sfm/cameras.json"), sfm_time);

  // A different (equivalent) boundary flag reruns boundary and what follows
  // it, not sfm.
  CommandResult changed = MakeRender("BOUNDARY_FLAGS='--verbose'");
  ASSERT_EQ(changed.exit_code, 0) << changed.output;
  EXPECT_EQ(changed.output.find("bin/sfm"), std::string::npos) << changed.output;
  EXPECT_NE(changed.output.find("bin/segment-boundary"), std::string::npos) << changed.output;
  EXPECT_NE(changed.output.find("bin/detect-features"), std::string::npos) << changed.output;
  EXPECT_NE(changed.output.find("bin/densify"), std::string::npos) << changed.output;
  EXPECT_EQ(MTime("10_sfm/cameras.json"), sfm_time);
  EXPECT_NE(MTime("20_boundary/boundary.json"), boundary_time);
  // Back to the default flags, with DENSIFY=0: boundary reruns once more, and
  // init-mesh and optimize fit sfm's points; back again, densify's; then stable.
  CommandResult sparse = MakeRender("DENSIFY=0");
  ASSERT_EQ(sparse.exit_code, 0) << sparse.output;
  EXPECT_NE(sparse.output.find("bin/segment-boundary"), std::string::npos) << sparse.output;
  EXPECT_EQ(sparse.output.find("bin/densify"), std::string::npos) << sparse.output;
  EXPECT_NE(sparse.output.find("--points " + (Work() / "10_sfm/points.ply").string()),
            std::string::npos)
      << sparse.output;
  CommandResult dense = MakeRender("");
  ASSERT_EQ(dense.exit_code, 0) << dense.output;
  EXPECT_EQ(dense.output.find("bin/segment-boundary"), std::string::npos) << dense.output;
  EXPECT_NE(dense.output.find("--points " + (Work() / "25_points/points.ply").string()),
            std::string::npos)
      << dense.output;
  CommandResult stable = MakeRender("");
  ASSERT_EQ(stable.exit_code, 0) << stable.output;
  for (const char* stage : {"bin/segment-boundary", "bin/densify", "bin/init-mesh", "bin/render"})
    EXPECT_EQ(stable.output.find(stage), std::string::npos) << stage << "\n" << stable.output;
}

TEST_F(Pipeline, FeaturesFromAnotherDetectorAreValidatedAndUsed) {
  // The perfect external detector: true lines projected into the reference view.
  auto gt = LoadGroundTruth(SampleDir(kSample));
  ASSERT_TRUE(gt);
  CameraSet sfm = ReadCameras(Work() / "10_sfm/cameras.json");
  const PinholeCamera* ref = gt->cameras.Find(sfm.reference);
  ASSERT_NE(ref, nullptr);
  Json doc = {{"format", "docunfold.features"}, {"version", 1}, {"segments", Json::array()}};
  for (const TrueLine& l : TrueLinesInView(*gt, *ref, 20.0)) {
    Json pts = Json::array();
    for (const auto& p : l.points) pts.push_back({p.x(), p.y()});
    doc["segments"].push_back({{"kind", l.kind == "text" ? "text" : "edge"}, {"points", pts}});
  }
  ASSERT_FALSE(doc["segments"].empty());
  const fs::path theirs = dir_.path() / "their_lines.json";
  std::ofstream(theirs) << doc.dump();
  CommandResult r = MakeRender("FEATURES=" + Quote(theirs.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("bin/detect-features"), std::string::npos) << r.output;
  EXPECT_EQ(ReadJsonFile(Work() / "30_features/features.json"), doc);

  // A wrong file stops with file:/json/pointer and leaves the last good one.
  Json bad = doc;
  bad["segments"][0]["kind"] = "baseline";
  const fs::path wrong = dir_.path() / "wrong.json";
  std::ofstream(wrong) << bad.dump();
  r = MakeRender("FEATURES=" + Quote(wrong.string()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("wrong.json:/segments/0/kind: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Error 3"), std::string::npos) << r.output;
  EXPECT_EQ(ReadJsonFile(Work() / "30_features/features.json"), doc);

  // Without FEATURES the detector runs again.
  r = Make("features");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("bin/detect-features"), std::string::npos) << r.output;
}

TEST(PipelineInput, UnknownDataSetIsReported) {
  CommandResult r =
      RunCommand("make --no-print-directory -f " + Quote((SourceDir() / "pipeline.mk").string()) +
                 " DATA=no-such-set WORK=/tmp/docunfold-none sfm");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("DATA=no-such-set: no data set"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists("/tmp/docunfold-none/10_sfm/cameras.json"));
  // A path with spaces that names nothing: the one line, and no warnings
  // from its words taken for targets.
  r = RunCommand("make --no-print-directory -f " + Quote((SourceDir() / "pipeline.mk").string()) +
                 " NO_BUILD=1 'DATA=/no such/letter 1' WORK_ROOT=/tmp/docunfold-none");
  EXPECT_EQ(r.exit_code, 2) << r.output;  // make's own code for a failed recipe
  EXPECT_NE(r.output.find("DATA=/no such/letter 1: no data set or folder of photos there"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
}

// A folder holding the photos of two pages (small copies of set01's and
// set04's): the page with more photos is made in WORK, the other in
// WORK_ROOT/<name>-p1 (its photos' names come first), and both are joined
// into WORK_ROOT/<name>.pdf in that order, the other page made with the same
// flags; a second make remakes nothing. With WORK=dir, the same beside dir.
TEST(PipelineInput, AFolderOfTwoPagesGivesOnePdfOfBoth) {
  if (!fs::is_directory(SampleDir("set01")) || !fs::is_directory(SampleDir("set04")))
    GTEST_SKIP() << "no samples set01 and set04";
  TempDir tmp;
  const fs::path photos = tmp / "Letter 3";
  fs::create_directories(photos);
  auto copy_views = [&](const std::string& set, int count, int first_number) {
    for (int i = 0; i < count; ++i) {
      const cv::Mat image = cv::imread(
          (SampleDir(set) / "images" / ("view_0" + std::to_string(i) + ".jpg")).string());
      ASSERT_FALSE(image.empty());
      cv::Mat small;
      cv::resize(image, small, cv::Size(800, image.rows * 800 / image.cols), 0, 0, cv::INTER_AREA);
      cv::imwrite((photos / ("IMG_00" + std::to_string(first_number + i) + ".jpg")).string(), small,
                  {cv::IMWRITE_JPEG_QUALITY, 92});
    }
  };
  copy_views("set04", 3, 10);  // IMG_0010-12: the other page, first by name
  copy_views("set01", 4, 20);  // IMG_0020-23: the page with more photos
  const fs::path work_root = tmp / "work";
  auto make = [&](const std::string& more = "") {
    return RunCommand(
        "make --no-print-directory -f " + Quote((SourceDir() / "pipeline.mk").string()) +
        " NO_BUILD=1 BUILD=" + Quote(fs::path(DOCUNFOLD_BIN_DIR).parent_path().string()) +
        " DATA=" + Quote(photos.string()) + " WORK_ROOT=" + Quote(work_root.string()) +
        " OPTIMIZE_FLAGS='--rounds 1'" + more + " all");  // (what is made where, not how well)
  };
  const CommandResult r = make();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto views = [&](const std::string& work) {
    const Json cameras = ReadJsonFile(work_root / work / "10_sfm/cameras.json");
    std::vector<std::string> names;
    for (const Json& v : cameras.at("views")) names.push_back(v.at("image"));
    std::sort(names.begin(), names.end());
    return names;
  };
  EXPECT_EQ(views("Letter_3"), (std::vector<std::string>{"IMG_0020.jpg", "IMG_0021.jpg",
                                                         "IMG_0022.jpg", "IMG_0023.jpg"}));
  EXPECT_EQ(views("Letter_3-p1"),
            (std::vector<std::string>{"IMG_0010.jpg", "IMG_0011.jpg", "IMG_0012.jpg"}));
  const CommandResult pages =
      RunCommand("qpdf --show-npages " + Quote((work_root / "Letter_3.pdf").string()));
  EXPECT_EQ(pages.output, "2\n") << r.output;
  EXPECT_TRUE(fs::exists(work_root / "Letter_3.alto/001-Letter_3-p1.alto.xml")) << r.output;
  EXPECT_TRUE(fs::exists(work_root / "Letter_3.alto/002-Letter_3.alto.xml")) << r.output;
  EXPECT_NE(ReadFileText(work_root / "Letter_3-p1/.flags/optimize").find("--rounds 1"),
            std::string::npos)
      << "the other page is made with the same flags";
  EXPECT_EQ(std::distance(fs::directory_iterator(photos), fs::directory_iterator()), 7)
      << "nothing is written beside the photos";

  const CommandResult again = make();
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(again.output.find("bin/"), std::string::npos) << again.output;
  EXPECT_EQ(again.output.find("book: wrote"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("all its pages in " + (work_root / "Letter_3.pdf").string()),
            std::string::npos)
      << again.output;

  // With WORK=dir the other pages go beside dir and the book is dir.pdf (the
  // work copied with its times, so that only what names the pages reruns).
  const fs::path moved = tmp / "scans" / "letter";
  fs::create_directories(moved.parent_path());
  ASSERT_EQ(
      RunCommand("cp -a " + Quote((work_root / "Letter_3").string()) + " " + Quote(moved.string()) +
                 " && cp -a " + Quote((work_root / "Letter_3-p1").string()) + " " +
                 Quote(moved.string() + "-p1"))
          .exit_code,
      0);
  const CommandResult elsewhere = make(" WORK=" + Quote(moved.string() + "/"));
  ASSERT_EQ(elsewhere.exit_code, 0) << elsewhere.output;
  EXPECT_EQ(RunCommand("qpdf --show-npages " + Quote(moved.string() + ".pdf")).output, "2\n")
      << elsewhere.output;
  EXPECT_TRUE(fs::exists(moved.string() + ".alto/001-letter-p1.alto.xml")) << elsewhere.output;
  EXPECT_TRUE(fs::exists(moved.string() + ".alto/002-Letter_3.alto.xml")) << elsewhere.output;
  EXPECT_TRUE(fs::exists(moved.string() + "-p1/80_pdf/letter-p1.pdf")) << elsewhere.output;
}

// A work root Make cannot carry (a space in it) is refused in one line before
// anything is written, not split into words that become stray folders.
TEST(PipelineInput, AWorkRootWithASpaceIsRefused) {
  TempDir tmp;
  CommandResult r =
      RunCommand("cd " + Quote(tmp.path().string()) + " && make --no-print-directory -f " +
                 Quote((SourceDir() / "pipeline.mk").string()) + " NO_BUILD=1 DATA=" + kSample +
                 " 'WORK_ROOT=scans/my work' sfm");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("WORK_ROOT=scans/my work: a path with a space"), std::string::npos)
      << r.output;
  EXPECT_EQ(std::distance(fs::directory_iterator(tmp.path()), fs::directory_iterator()), 0)
      << "nothing is written";
}

// DATA may name a folder of photos without images/ (as a phone or an app
// exports them; read where they are, through WORK/.photos/images) or a data
// set's images/ folder (its data set). A dry run shows what sfm is given. A
// folder of folders is refused in one line. A work root inside the photos
// folder is not taken for a change of the photos.
TEST(PipelineInput, AFolderOfPhotosOrADataSetsImagesFolder) {
  TempDir tmp;
  const fs::path photos = tmp / "Letter 2";
  fs::create_directories(photos);
  for (const auto& entry : fs::directory_iterator(SampleDir(kSample) / "images"))
    fs::copy_file(entry.path(), photos / entry.path().filename());
  auto dry_run = [&](const fs::path& data) {
    return RunCommand("make --no-print-directory -n -f " +
                      Quote((SourceDir() / "pipeline.mk").string()) +
                      " NO_BUILD=1 DATA=" + Quote(data.string()) +
                      " WORK_ROOT=" + Quote((tmp / "work").string()) + " sfm");
  };
  CommandResult r = dry_run(photos);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path work = tmp / "work/Letter_2";
  EXPECT_NE(r.output.find("--data " + (work / ".photos").string() + " "), std::string::npos)
      << r.output;
  EXPECT_EQ(fs::read_symlink(work / ".photos/images"), fs::canonical(photos));
  EXPECT_EQ(std::distance(fs::directory_iterator(photos), fs::directory_iterator()),
            std::distance(fs::directory_iterator(SampleDir(kSample) / "images"),
                          fs::directory_iterator()))
      << "nothing is written beside the photos";

  // A work root inside the photos folder: another data set's work directory
  // made there is no change of the photos, so sfm would not rerun.
  const fs::path scans = tmp / "scans";
  fs::create_directories(scans);
  for (const auto& entry : fs::directory_iterator(photos))
    fs::copy_file(entry.path(), scans / entry.path().filename());
  auto dry_run_inside = [&] {
    return RunCommand("make --no-print-directory -n -f " +
                      Quote((SourceDir() / "pipeline.mk").string()) +
                      " NO_BUILD=1 DATA=" + Quote(scans.string()) +
                      " WORK_ROOT=" + Quote((scans / "work").string()) + " sfm");
  };
  ASSERT_EQ(dry_run_inside().exit_code, 0);
  const std::string digest = ReadFileText(scans / "work/scans/.flags/images");
  EXPECT_FALSE(digest.empty());
  fs::create_directories(scans / "work/letter/.flags");
  ASSERT_EQ(dry_run_inside().exit_code, 0);
  EXPECT_EQ(ReadFileText(scans / "work/scans/.flags/images"), digest);

  r = dry_run(SampleDir(kSample) / "images");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("--data " + fs::canonical(SampleDir(kSample)).string() + " "),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("--out " + (tmp / "work" / kSample / "10_sfm").string()),
            std::string::npos)
      << r.output;

  // A box of documents (folders only): one line saying what a run takes.
  fs::create_directories(tmp / "box/letter 3");
  fs::rename(photos, tmp / "box" / photos.filename());
  r = RunCommand("make --no-print-directory -f " + Quote((SourceDir() / "pipeline.mk").string()) +
                 " NO_BUILD=1 DATA=" + Quote((tmp / "box").string()) +
                 " WORK_ROOT=" + Quote((tmp / "work").string()) + " sfm");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("box: no photos in it (a run takes one document's photos;"),
            std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace docunfold::testing
