// Photos as phones and people hand them over (phone_photos.h), each case
// made from set01's photos and run through pipeline.mk as a user would:
// the result must be as good as set01's own (the e2e run's), nothing may be
// written outside WORK_ROOT/<name>/, and the data set must stay as it was.
#include "tests/pipeline/phone_photos.h"

#include <gtest/gtest.h>

#include <algorithm>
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

// Straight from a phone: EXIF-tagged portrait photos and HEIC ones beside
// an iPhone's sidecar file, named as phones and apps name them, in
// "My Scans/lettre é 1", run from inside its images/ folder with DATA=..
// (Each case is a whole pipeline run, about a minute of CI: the awkward
// properties share two data sets instead of having one each.)
TEST_F(PhonePhotos, PortraitAndHeicPhotosWithASidecarSpacedNamesAndDataDotDot) {
  PhoneChanges c;
  c.exif_portrait = {0, 1, 2};
  c.heic = {3, 4};
  c.sidecar = true;
  c.spaced_names = true;
  const fs::path set = tmp_ / "My Scans" / "lettre é 1";
  EXPECT_GT(Run(c, set, set / "images", "..", "lettre_é_1"), own_ - kTolerance) << output_;
  EXPECT_TRUE(Said("left out: IMG_0001.AAE (not a photo)")) << output_;
  EXPECT_TRUE(fs::exists(tmp_ / "work/lettre_é_1/60_render/rectified.png"));
  const Json cameras = ReadJsonFile(tmp_ / "work/lettre_é_1/10_sfm/cameras.json");
  std::map<std::string, int> width;
  for (const Json& view : cameras.at("views")) width[view.at("image")] = view.at("width");
  EXPECT_EQ(width.size(), 5u) << "every photo read, HEIC too";
  EXPECT_EQ(width["IMG 0003 (copie).jpg"], 1200) << "upright: portrait";
  EXPECT_EQ(width["naïve ñ 5.heic"], 1600) << "HEIC, untagged: landscape";
  double focal_prior = 0;
  for (const Json& camera : cameras.at("colmap").at("cameras"))
    focal_prior = std::max(focal_prior, camera.at("focal_prior_px").get<double>());
  EXPECT_GT(focal_prior, 0) << "the EXIF focal length is COLMAP's prior";
}

// Photos turned in their pixels (no tag), one of them from a 48-megapixel
// phone, one at half size, and one damaged by an interrupted copy: the
// damaged photo is left out, by name, and the pipeline goes on with the
// other four; run with DATA=. from the set's folder.
TEST_F(PhonePhotos, TurnedPhotosOneFromA48MegapixelPhoneOneAtHalfSizeOneTruncated) {
  PhoneChanges c;
  c.turned = {1, 3};
  c.scale[3] = 5;  // 8000 x 6000, then turned
  c.scale[4] = 0.5;
  c.truncated = {0};
  const fs::path set = tmp_ / "letter1";
  const double ms_ssim = Run(c, set, set, ".", "letter1");
  EXPECT_TRUE(Said("left out: view_00.jpg (damaged: the file ends early)")) << output_;
  EXPECT_GT(ms_ssim, own_ - kTolerance) << output_;
  const Json cameras = ReadJsonFile(tmp_ / "work/letter1/10_sfm/cameras.json");
  EXPECT_EQ(cameras.at("views").size(), 4u);
  EXPECT_EQ(cameras.at("left_out").at(0).at("image"), "view_00.jpg");
  // The turned photos, the large one among them, are copied for COLMAP at
  // one size and share a camera with the untouched one; the small one has
  // its own.
  EXPECT_EQ(cameras.at("colmap").at("cameras").size(), 2u);
}

}  // namespace
}  // namespace docunfold::testing
