// The sfm command line: a good run on a small copy of a data set, --ref,
// replacing an earlier output, and every kind of bad input (exit code, one
// line naming the cause, no partial output left behind).
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "common/camera.h"
#include "common/json_io.h"
#include "common/ply.h"
#include "common/subprocess.h"
#include "tests/pipeline/phone_photos.h"
#include "tests/sfm/sfm_eval.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

CommandResult Sfm(const std::string& args) {
  return RunCommand(Quote(StageBinary("sfm").string()) + " " + args);
}

std::string Args(const fs::path& data, const fs::path& out, const std::string& more = "") {
  return "--data " + Quote(data.string()) + " --out " + Quote(out.string()) +
         (more.empty() ? "" : " " + more);
}

// Names of everything directly in `dir`.
std::set<std::string> Listing(const fs::path& dir) {
  std::set<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) names.insert(e.path().filename().string());
  return names;
}

int CountLines(const std::string& s) { return int(std::count(s.begin(), s.end(), '\n')); }

// A failed run: the exit code, exactly one line on stderr saying what is
// wrong (containing `needle`), and nothing left in `out`'s parent that was
// not there before.
void ExpectFailure(const CommandResult& r, int code, const std::string& needle, const fs::path& out,
                   const std::set<std::string>& parent_before) {
  EXPECT_EQ(r.exit_code, code) << r.output;
  EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
  // Our progress lines are allowed before the error; the error is one line.
  const std::regex error_line("^sfm: (bad input|usage error|error|cannot write output): ");
  int errors = 0;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) errors += std::regex_search(line, error_line);
  EXPECT_EQ(errors, 1) << r.output;
  EXPECT_EQ(Listing(out.parent_path()), parent_before) << "left behind in " << out.parent_path();
}

cv::Mat Noise(int w, int h, unsigned seed) {
  cv::Mat im(h, w, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(im, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(im, im, cv::Size(3, 3), 0);
  return im;
}

class SfmCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(StageBinary("sfm"))) GTEST_SKIP() << "sfm not built";
  }
  // 3 views of a data set with ground truth at 800 px: a quick real run.
  fs::path SmallSet(int views = 3) {
    const fs::path source = AnyDataSet();
    if (source.empty()) return {};
    return MakeSmallDataSet(source, tmp_ / "small", views, 800);
  }
  bool HaveColmap() const { return !FindExecutable("colmap").empty(); }
  TempDir tmp_;
};

TEST_F(SfmCli, HelpListsFlagsWithDefaults) {
  const CommandResult r = Sfm("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* s : {"--data", "--out", "--ref", "--max-image-size", "1600", "--camera-model",
                        "SIMPLE_RADIAL", "--threads", "--verbose", "--max-reprojection-error",
                        "--min-points", "--colmap", "Exit codes"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s;
}

TEST_F(SfmCli, UsageErrorsExit2) {
  const fs::path out = tmp_ / "out";
  for (const std::string& args :
       {std::string("--out ") + Quote(out.string()), std::string("--data x"),
        Args("x", out, "--camera-model FISHEYE"), Args("x", out, "--max-image-size 0"),
        Args("x", out, "--no-such-flag"), Args("x", out, "--threads many"),
        Args("x", out, "--matcher flann")}) {
    const CommandResult r = Sfm(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST_F(SfmCli, NoDataSetFolder) {
  const fs::path out = tmp_ / "work" / "10_sfm";
  fs::create_directories(out.parent_path());
  ExpectFailure(Sfm(Args(tmp_ / "missing", out)), 3, (tmp_ / "missing").string(), out, {});
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(SfmCli, NoImagesFolder) {
  fs::create_directories(tmp_ / "set" / "ground_truth");
  const fs::path out = tmp_ / "work" / "10_sfm";
  fs::create_directories(out.parent_path());
  ExpectFailure(Sfm(Args(tmp_ / "set", out)), 3, "images", out, {});
}

TEST_F(SfmCli, FewerThanTwoImages) {
  fs::create_directories(tmp_ / "set" / "images");
  cv::imwrite((tmp_ / "set" / "images" / "only.jpg").string(), Noise(64, 48, 1));
  const fs::path out = tmp_ / "work" / "10_sfm";
  fs::create_directories(out.parent_path());
  ExpectFailure(Sfm(Args(tmp_ / "set", out)), 3, "at least 2", out, {});
}

TEST_F(SfmCli, FilesThatAreNotPhotosAreLeftOutByName) {
  fs::create_directories(tmp_ / "set" / "images");
  cv::imwrite((tmp_ / "set" / "images" / "a.jpg").string(), Noise(64, 48, 1));
  std::ofstream(tmp_ / "set" / "images" / "broken.jpg") << "\xff\xd8 this is not a JPEG";
  std::ofstream(tmp_ / "set" / "images" / "empty.png");
  const fs::path out = tmp_ / "work" / "10_sfm";
  fs::create_directories(out.parent_path());
  const CommandResult r = Sfm(Args(tmp_ / "set", out));
  ExpectFailure(r, 3, "1 photo (2 files left out)", out, {});
  EXPECT_NE(r.output.find("left out: broken.jpg (not a photo)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("left out: empty.png (not a photo)"), std::string::npos) << r.output;
}

// Photos of different sizes get a camera each; a photo turned to portrait
// shares the camera of its landscape siblings; names keep their spaces and
// accents in cameras.json while COLMAP works on plain copies (so the exact
// matcher still runs).
TEST_F(SfmCli, MixedSizesTurnedPhotosAndSpacedNames) {
  if (!HaveColmap()) GTEST_SKIP() << "COLMAP not installed";
  const fs::path data = SmallSet(4);
  if (data.empty()) GTEST_SKIP() << "no data set with ground truth";
  std::vector<fs::path> photos;
  for (const auto& e : fs::directory_iterator(data / "images")) photos.push_back(e.path());
  std::sort(photos.begin(), photos.end());
  cv::Mat turned;
  cv::rotate(cv::imread(photos[1].string()), turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  cv::imwrite(photos[1].string(), turned);
  const cv::Mat big = cv::imread(photos[2].string());
  cv::Mat small;
  cv::resize(big, small, cv::Size(), 0.75, 0.75, cv::INTER_AREA);
  cv::imwrite(photos[2].string(), small);
  const std::string spaced = "Photo 2026-11-28 10.15 \xc3\xa9t\xc3\xa9.jpg";
  fs::rename(photos[0], data / "images" / spaced);
  // A phone's edited copy of the last photo, beside it: cropped, turned and
  // brightened. It is one shot, no second view, and is left out.
  const cv::Mat last = cv::imread(photos[3].string());
  cv::Mat edited;
  cv::rotate(last(cv::Rect(last.cols / 10, last.rows / 8, last.cols * 3 / 4, last.rows * 3 / 4)),
             edited, cv::ROTATE_90_CLOCKWISE);
  edited.convertTo(edited, -1, 1.15, 10);
  const std::string copy = photos[3].stem().string() + "_edited.jpg";
  cv::imwrite((data / "images" / copy).string(), edited);
  // A scanner app's copy of it too: the page alone, straightened. Its frame
  // lies inside the photos that show the whole page, and it is left out.
  const std::optional<GroundTruth> gt = LoadGroundTruth(AnyDataSet());
  ASSERT_TRUE(gt);
  const PinholeCamera* shot = gt->cameras.Find(photos[3].filename().string());
  ASSERT_NE(shot, nullptr);
  std::vector<cv::Point2f> page;  // (the small set's photos are scaled down)
  for (const Eigen::Vector2d& c : TrueCorners(*gt, *shot))
    page.emplace_back(c.x() * last.cols / shot->width, c.y() * last.cols / shot->width);
  const cv::Size scan_size(420, 594);
  cv::Mat scan;
  cv::warpPerspective(
      last, scan,
      cv::getPerspectiveTransform(
          page, std::vector<cv::Point2f>{{0, 0},
                                         {float(scan_size.width), 0},
                                         {float(scan_size.width), float(scan_size.height)},
                                         {0, float(scan_size.height)}}),
      scan_size, cv::INTER_CUBIC);
  const std::string scanned = "Scan 2026-12-06 10.15.jpg";
  cv::imwrite((data / "images" / scanned).string(), scan);
  const fs::path out = tmp_ / "work" / "10_sfm";
  const CommandResult r = Sfm(Args(data, out, "--threads 2"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("left out: " + copy + " (the same shot as " +
                          photos[3].filename().string() + ", edited"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(out / "colmap/exhaustive_matcher.log")) << "the exact matcher ran";
  const CameraSet cameras = ReadCameras(out / "cameras.json");
  ASSERT_EQ(cameras.views.size(), 4u) << r.output;
  const PinholeCamera* first = cameras.Find(spaced);
  const PinholeCamera* portrait = cameras.Find(photos[1].filename().string());
  const PinholeCamera* reduced = cameras.Find(photos[2].filename().string());
  ASSERT_TRUE(first && portrait && reduced);
  EXPECT_EQ(portrait->width, turned.cols);
  EXPECT_EQ(portrait->height, turned.rows);
  EXPECT_EQ(reduced->width, small.cols);
  // One lens: the turned photo has the same focal length, the smaller one
  // three quarters of it.
  EXPECT_NEAR(portrait->K(0, 0), first->K(0, 0), 1e-6 * first->K(0, 0));
  EXPECT_NEAR(reduced->K(0, 0) / first->K(0, 0), 0.75, 0.03);
  const Json doc = ReadJsonFile(out / "cameras.json");
  EXPECT_EQ(doc.at("colmap").at("cameras").size(), 2u);
  EXPECT_NE(r.output.find("left out: " + scanned + " (all of it lies within "), std::string::npos)
      << r.output;
  ASSERT_EQ(doc.at("left_out").size(), 2u) << doc.at("left_out").dump();
  for (const Json& left : doc.at("left_out")) {
    if (left.at("image") == copy)
      EXPECT_EQ(left.at("reason"), "the same shot as " + photos[3].filename().string() +
                                       ", edited or taken from the same spot");
    else
      EXPECT_EQ(left.at("image"), scanned);
  }
  EXPECT_TRUE(doc.at("colmap").at("not_mapped").empty());
  // Asked for as the reference, the copy is refused in one line.
  const std::set<std::string> before = Listing(out.parent_path());
  ExpectFailure(Sfm(Args(data, tmp_ / "work" / "copy_ref", "--threads 2 --ref " + copy)), 3,
                "--ref " + copy + ": left out as the same shot as", tmp_ / "work" / "copy_ref",
                before);
  // A photo and its scan alone are one view: sfm stops before mapping them
  // (they would give a page no better than the scan's own straightening).
  const fs::path pair = tmp_ / "pair";
  fs::create_directories(pair / "images");
  fs::copy_file(photos[3], pair / "images" / photos[3].filename());
  fs::copy_file(data / "images" / scanned, pair / "images" / scanned);
  ExpectFailure(Sfm(Args(pair, tmp_ / "work" / "pair", "--threads 2")), 3,
                "1 photo (1 file left out); sfm needs at least 2 views", tmp_ / "work" / "pair",
                before);
}

TEST_F(SfmCli, RefThatDoesNotExist) {
  fs::create_directories(tmp_ / "set" / "images");
  cv::imwrite((tmp_ / "set" / "images" / "a.jpg").string(), Noise(64, 48, 1));
  cv::imwrite((tmp_ / "set" / "images" / "b.jpg").string(), Noise(64, 48, 2));
  const fs::path out = tmp_ / "work" / "10_sfm";
  fs::create_directories(out.parent_path());
  ExpectFailure(Sfm(Args(tmp_ / "set", out, "--ref c.jpg")), 3, "c.jpg", out, {});
}

TEST_F(SfmCli, ColmapMissingSaysHowToInstallIt) {
  fs::create_directories(tmp_ / "set" / "images");
  cv::imwrite((tmp_ / "set" / "images" / "a.jpg").string(), Noise(64, 48, 1));
  cv::imwrite((tmp_ / "set" / "images" / "b.jpg").string(), Noise(64, 48, 2));
  const fs::path out = tmp_ / "work" / "10_sfm";
  fs::create_directories(out.parent_path());
  ExpectFailure(Sfm(Args(tmp_ / "set", out, "--colmap /nonexistent/colmap")), 1,
                "apt-get install colmap", out, {});
  // Not in PATH either.
  const CommandResult r = RunCommand("PATH=/nonexistent " + Quote(StageBinary("sfm").string()) +
                                     " " + Args(tmp_ / "set", out));
  ExpectFailure(r, 1, "scripts/install-deps.sh", out, {});
}

TEST_F(SfmCli, RefusesToReplaceAFolderItDidNotWrite) {
  fs::create_directories(tmp_ / "set" / "images");
  cv::imwrite((tmp_ / "set" / "images" / "a.jpg").string(), Noise(64, 48, 1));
  cv::imwrite((tmp_ / "set" / "images" / "b.jpg").string(), Noise(64, 48, 2));
  const fs::path out = tmp_ / "home";
  fs::create_directories(out);
  std::ofstream(out / "thesis.tex") << "precious";
  const CommandResult r = Sfm(Args(tmp_ / "set", out));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("not an sfm output"), std::string::npos) << r.output;
  EXPECT_EQ(Listing(out), std::set<std::string>{"thesis.tex"});
}

TEST_F(SfmCli, NothingRegisters) {
  if (!HaveColmap()) GTEST_SKIP() << "COLMAP not installed";
  fs::create_directories(tmp_ / "set" / "images");
  cv::imwrite((tmp_ / "set" / "images" / "a.jpg").string(), Noise(320, 240, 1));
  cv::imwrite((tmp_ / "set" / "images" / "b.jpg").string(), Noise(320, 240, 2));
  const fs::path out = tmp_ / "work" / "10_sfm";
  fs::create_directories(out.parent_path());
  ExpectFailure(Sfm(Args(tmp_ / "set", out)), 3, "fewer than 2 views registered", out, {});
}

TEST_F(SfmCli, GoodRunThenRefThenFailedRunKeepsTheOutput) {
  if (!HaveColmap()) GTEST_SKIP() << "COLMAP not installed";
  const fs::path data = SmallSet();
  if (data.empty()) GTEST_SKIP() << "no data set with ground truth";
  const fs::path out = tmp_ / "work" / "10_sfm";
  const CommandResult r = Sfm(Args(data, out, "--threads 2"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Progress, not COLMAP's chatter: a few dozen lines at most, all ours.
  EXPECT_LT(CountLines(r.output), 30) << r.output;
  EXPECT_EQ(r.output.find('\r'), std::string::npos);
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) EXPECT_EQ(line.rfind("sfm: ", 0), 0u) << line;
  EXPECT_NE(r.output.find("sfm: extracting features"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("3/3 views registered"), std::string::npos) << r.output;
  EXPECT_EQ(Listing(out.parent_path()), std::set<std::string>{"10_sfm"});
  for (const char* f :
       {"cameras.json", "points.ply", "reference.png", "colmap/database.db",
        "colmap/sparse/0/cameras.bin", "colmap/sparse/0/images.bin", "colmap/sparse/0/points3D.bin",
        "colmap/feature_extractor.log", "colmap/matches_raw.txt", "colmap/matches_importer.log",
        "colmap/mapper.log"})
    EXPECT_TRUE(fs::is_regular_file(out / f)) << f;
  const CameraSet first = ReadCameras(out / "cameras.json");
  EXPECT_EQ(first.views.size(), 3u);
  const PlyData ply = ReadPly(out / "points.ply");
  EXPECT_GE(ply.vertices.size(), 100u);
  EXPECT_TRUE(std::any_of(ply.comments.begin(), ply.comments.end(), [](const std::string& c) {
    return c.find("reference view") != std::string::npos;
  }));

  // --ref: another view becomes the frame; the old output is replaced (the
  // folder named with a trailing slash, as a shell's completion writes it).
  std::string other;
  for (const PinholeCamera& c : first.views)
    if (c.image != first.reference) other = c.image;
  const CommandResult r2 = Sfm(Args(data, out / "", "--threads 2 --ref " + other));
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  const CameraSet second = ReadCameras(out / "cameras.json");
  EXPECT_EQ(second.reference, other);
  EXPECT_TRUE(second.Find(other)->R.isIdentity(0));
  EXPECT_TRUE(second.Find(other)->t.isZero(0));
  EXPECT_EQ(Listing(out.parent_path()), std::set<std::string>{"10_sfm"});

  // Exact matching and a mapper on one thread: the same photos give the same
  // points byte for byte, and the same cameras to the last bit.
  auto read_bytes = [](const fs::path& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  };
  auto cameras_without_times = [](const fs::path& f) {
    Json cameras = ReadJsonFile(f);
    cameras.erase("seconds");
    for (Json& attempt : cameras["colmap"]["mapper_attempts"]) attempt.erase("seconds");
    return cameras;
  };
  const std::string points = read_bytes(out / "points.ply");
  const Json cameras = cameras_without_times(out / "cameras.json");
  ASSERT_EQ(Sfm(Args(data, out, "--threads 2 --ref " + other)).exit_code, 0);
  EXPECT_EQ(read_bytes(out / "points.ply"), points);
  EXPECT_EQ(cameras_without_times(out / "cameras.json"), cameras);
  // COLMAP's own matcher stays available.
  const CommandResult r3 = Sfm(Args(data, out, "--threads 2 --matcher colmap"));
  ASSERT_EQ(r3.exit_code, 0) << r3.output;
  EXPECT_TRUE(fs::is_regular_file(out / "colmap/exhaustive_matcher.log"));
  EXPECT_FALSE(fs::exists(out / "colmap/matches_raw.txt"));

  // A failing run leaves the last good output as it was.
  std::ifstream before_file(out / "cameras.json");
  const std::string before((std::istreambuf_iterator<char>(before_file)), {});
  ExpectFailure(Sfm(Args(data, out, "--ref missing.jpg")), 3, "missing.jpg", out, {"10_sfm"});
  std::ifstream after_file(out / "cameras.json");
  const std::string after((std::istreambuf_iterator<char>(after_file)), {});
  EXPECT_EQ(before, after);
}

TEST_F(SfmCli, RefNotRegistered) {
  if (!HaveColmap()) GTEST_SKIP() << "COLMAP not installed";
  const fs::path data = SmallSet(3);
  if (data.empty()) GTEST_SKIP() << "no data set with ground truth";
  const cv::Mat sample = cv::imread((*fs::directory_iterator(data / "images")).path().string());
  cv::imwrite((data / "images" / "zz_noise.jpg").string(), Noise(sample.cols, sample.rows, 3));
  const fs::path out = tmp_ / "work" / "10_sfm";
  fs::create_directories(out.parent_path());
  const CommandResult r = Sfm(Args(data, out, "--threads 2 --ref zz_noise.jpg"));
  ExpectFailure(r, 3, "could not register", out, {});
  // It shares no features with the page's photos: the mapper is not given it.
  EXPECT_NE(r.output.find("2 groups with no features in common"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" and 2 more; zz_noise.jpg; mapping the first"), std::string::npos)
      << r.output;
}

TEST_F(SfmCli, TooFewPoints) {
  if (!HaveColmap()) GTEST_SKIP() << "COLMAP not installed";
  const fs::path data = SmallSet(3);
  if (data.empty()) GTEST_SKIP() << "no data set with ground truth";
  const fs::path out = tmp_ / "work" / "10_sfm";
  fs::create_directories(out.parent_path());
  const CommandResult r = Sfm(Args(data, out, "--threads 2 --no-retry --min-points 1000000"));
  ExpectFailure(r, 3, "fewer than --min-points 1000000", out, {});
  EXPECT_TRUE(std::regex_search(r.output, std::regex("only \\d+ 3D points"))) << r.output;
}

// Two photos of a creased page. The mapper alone lets the focal length run
// off on this page, a page being nearly a plane: to 2,339 px against the
// true 1,160 from EXIF's prior, to 2,897 px from COLMAP's default guess. As a
// phone tags them (EXIF 35 mm focal length, rounded to a millimetre), sfm
// keeps EXIF's; without EXIF, it maps them again with a phone's 26 mm.
TEST_F(SfmCli, TwoPhotosKeepAPhonesFocalLength) {
  if (!HaveColmap()) GTEST_SKIP() << "COLMAP not installed";
  if (!fs::exists(StageBinary("synth"))) GTEST_SKIP() << "synth not built";
  const fs::path page = tmp_ / "page";
  const CommandResult made =
      RunCommand(Quote(StageBinary("synth").string()) + " --seed 864 --kind text --views 2 --out " +
                 Quote(page.string()));
  ASSERT_EQ(made.exit_code, 0) << made.output;
  PhoneChanges phone;
  phone.exif_portrait = {0, 1};
  MakePhoneSet(page, tmp_ / "phone", phone);
  const double truth =
      ReadJsonFile(page / "ground_truth/cameras.json").at("views").at(0).at("K").at(0).at(0);
  for (const std::string name : {"phone", "page"}) {
    SCOPED_TRACE(name);
    const fs::path out = tmp_ / "work" / name;
    const CommandResult r = Sfm(Args(tmp_ / name, out, "--threads 2"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const Json colmap = ReadJsonFile(out / "cameras.json").at("colmap");
    const Json& attempts = colmap.at("mapper_attempts");
    const std::string kept = attempts.back().at("setting");
    EXPECT_NE(kept.find("focal length fixed"), std::string::npos) << kept;
    if (name == "page") {
      ASSERT_EQ(attempts.size(), 2u) << r.output;
      EXPECT_NE(attempts[0].at("problem").get<std::string>().find("two photos do not fix it"),
                std::string::npos);
    }
    const CameraSet cameras = ReadCameras(out / "cameras.json");
    ASSERT_EQ(cameras.views.size(), 2u) << r.output;
    // EXIF's 25 mm is 0.4 % off the truth, a phone's 26 mm 3.6 %.
    for (const PinholeCamera& view : cameras.views)
      EXPECT_NEAR(view.K(0, 0) / truth, 1, name == "phone" ? 0.01 : 0.05) << view.image;
  }
}

}  // namespace
}  // namespace docunfold::testing
