// Photos as phones and people hand them over (phone_photos.h), each case
// made from set01's photos and run through pipeline.mk as a user would:
// the result must be as good as set01's own (the e2e run's), nothing may be
// written outside WORK_ROOT/<name>/, and the data set must stay as it was.
#include "tests/pipeline/phone_photos.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "common/json_io.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

// How far below set01's own MS-SSIM a changed set may score.
constexpr double kTolerance = 0.02;

// Every file under `dir` (recursively) with its size and modification time.
std::map<std::string, std::string> Listing(const fs::path& dir) {
  std::map<std::string, std::string> out;
  if (!fs::exists(dir)) return out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    std::string what = e.is_regular_file() ? std::to_string(e.file_size()) : "dir";
    what += " " + std::to_string(e.last_write_time().time_since_epoch().count());
    out[fs::relative(e.path(), dir).string()] = what;
  }
  return out;
}

class PhonePhotos : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::is_directory(SampleDir("set01"))) GTEST_SKIP() << "no sample set01";
    ASSERT_TRUE(fs::exists(E2eDir() / "results.json")) << "did the e2e_run fixture run?";
    own_ = Metric(E2eRows("set01"), "docunfold", "ms_ssim");  // the benchmark's docunfold row
    ASSERT_FALSE(std::isnan(own_)) << "no set01 result in the e2e run";
  }

  // Makes the changed set at `set` and runs `make all` from `cwd` with
  // DATA=`data`; checks that only WORK_ROOT/`name`/ was written and the data
  // set is unchanged; returns the result's MS-SSIM.
  double Run(const PhoneChanges& changes, const fs::path& set, const fs::path& cwd,
             const std::string& data, const std::string& name) {
    MakePhoneSet(SampleDir("set01"), set, changes);
    const fs::path work_root = tmp_ / "work";
    const auto data_before = Listing(set);
    const auto top_before = Listing(tmp_.path());
    output_ = RunCommand("cd " + Quote(cwd.string()) + " && make --no-print-directory -f " +
                         Quote((SourceDir() / "pipeline.mk").string()) + " DATA=" + Quote(data) +
                         " WORK_ROOT=" + Quote(work_root.string()) + " NO_BUILD=1 BUILD=" +
                         Quote(fs::path(DOCUNFOLD_BIN_DIR).parent_path().string()) +
                         " EVAL_FLAGS=--no-ocr all")
                  .output;
    EXPECT_EQ(Listing(set), data_before) << "the data set changed";
    std::vector<std::string> roots;
    for (const auto& e : fs::directory_iterator(work_root)) roots.push_back(e.path().filename());
    EXPECT_EQ(roots, std::vector<std::string>{name}) << output_;
    for (const auto& [path, what] : Listing(tmp_.path())) {
      if (path.rfind("work", 0) != 0) {
        EXPECT_TRUE(top_before.count(path)) << path << " written outside the work directory";
      }
    }
    const fs::path metrics = work_root / name / "70_eval/metrics.json";
    if (!fs::exists(metrics)) {
      ADD_FAILURE() << "no result:\n" << output_;
      return NAN;
    }
    const double ms_ssim = ReadJsonFile(metrics).at("metrics").at("ms_ssim").get<double>();
    RecordProperty("ms_ssim", std::to_string(ms_ssim));
    std::cout << "MS-SSIM " << ms_ssim << " (set01's own " << own_ << ")\n";
    return ms_ssim;
  }
  bool Said(const std::string& text) const { return output_.find(text) != std::string::npos; }

  TempDir tmp_;
  double own_ = NAN;
  std::string output_;
};

// EXIF-tagged portrait photos named as phones and apps name them, in
// "My Scans/lettre é 1", run from inside its images/ folder with DATA=..
TEST_F(PhonePhotos, ExifTaggedPortraitPhotosWithSpacedNamesAndDataDotDot) {
  PhoneChanges c;
  c.exif_portrait = {0, 1, 2, 3, 4};
  c.spaced_names = true;
  const fs::path set = tmp_ / "My Scans" / "lettre é 1";
  EXPECT_GT(Run(c, set, set / "images", "..", "lettre_é_1"), own_ - kTolerance) << output_;
  EXPECT_TRUE(fs::exists(tmp_ / "work/lettre_é_1/60_render/rectified.png"));
  const Json cameras = ReadJsonFile(tmp_ / "work/lettre_é_1/10_sfm/cameras.json");
  EXPECT_EQ(cameras.at("views").at(0).at("width").get<int>(), 1200) << "upright: portrait";
  EXPECT_GT(cameras.at("colmap").at("cameras").at(0).at("focal_prior_px").get<double>(), 0);
}

TEST_F(PhonePhotos, TurnedPhotosAndOneAtHalfSize) {
  PhoneChanges c;
  c.turned = {1, 3};
  c.scale[4] = 0.5;
  const fs::path set = tmp_ / "mixed";
  EXPECT_GT(Run(c, set, tmp_.path(), set.string(), "mixed"), own_ - kTolerance) << output_;
  const Json cameras = ReadJsonFile(tmp_ / "work/mixed/10_sfm/cameras.json");
  EXPECT_EQ(cameras.at("colmap").at("cameras").size(), 2u) << "the turned ones share a camera";
}

// One photo from a 48-megapixel phone and one damaged by an interrupted
// copy: the damaged photo is left out, by name, and the pipeline goes on
// with the other four; run with DATA=. from the set's folder.
TEST_F(PhonePhotos, OnePhotoFromA48MegapixelPhoneOneTruncatedAndDataDot) {
  PhoneChanges c;
  c.scale[3] = 5;  // 8000 x 6000
  c.truncated = {0};
  const fs::path set = tmp_ / "letter1";
  const double ms_ssim = Run(c, set, set, ".", "letter1");
  EXPECT_TRUE(Said("left out: view_00.jpg (damaged: the file ends early)")) << output_;
  EXPECT_GT(ms_ssim, own_ - kTolerance) << output_;
  const Json cameras = ReadJsonFile(tmp_ / "work/letter1/10_sfm/cameras.json");
  EXPECT_EQ(cameras.at("views").size(), 4u);
  EXPECT_EQ(cameras.at("left_out").at(0).at("image"), "view_00.jpg");
}

TEST_F(PhonePhotos, HeicPhotosAndASidecarFile) {
  PhoneChanges c;
  c.heic = {0, 1, 2, 3, 4};
  c.sidecar = true;
  const fs::path set = tmp_ / "iphone";
  EXPECT_GT(Run(c, set, tmp_.path(), set.string(), "iphone"), own_ - kTolerance) << output_;
  EXPECT_TRUE(Said("left out: IMG_0001.AAE (not a photo)")) << output_;
}

}  // namespace
}  // namespace docunfold::testing
