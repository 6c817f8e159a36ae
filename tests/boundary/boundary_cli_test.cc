// The segment-boundary command line: outputs and their formats, --verbose,
// and bad input (missing or unreadable image, an image without a document)
// failing with exit 3, a message naming the file, and no output at all.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/json_io.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

std::string Binary() { return Quote(StageBinary("segment-boundary").string()); }

// A page on a green table, written as PNG.
fs::path WriteScene(const TempDir& dir, bool with_page) {
  cv::Mat3b image(600, 800, cv::Vec3b(70, 110, 60));
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0, 3);
  if (with_page) {
    std::vector<cv::Point> page = {{250, 100}, {560, 130}, {540, 520}, {230, 500}};
    cv::fillConvexPoly(image, page, cv::Scalar(235, 238, 240));
    for (int y = 160; y < 470; y += 14)
      cv::line(image, {280, y}, {500, y + 10}, cv::Scalar(40, 40, 40), 2);
  }
  image.forEach([&](cv::Vec3b& p, const int*) {
    for (int c = 0; c < 3; ++c) p[c] = cv::saturate_cast<uchar>(p[c] + noise(rng));
  });
  const fs::path path = dir / (with_page ? "page.png" : "table.png");
  cv::imwrite(path.string(), image);
  return path;
}

bool Empty(const fs::path& dir) {
  return !fs::exists(dir) || fs::directory_iterator(dir) == fs::directory_iterator();
}

TEST(SegmentBoundaryCli, WritesMaskBoundaryAndOverlay) {
  TempDir dir;
  const fs::path image = WriteScene(dir, true);
  const CommandResult r = RunCommand(Binary() + " --image " + Quote(image.string()) + " --out " +
                                     Quote((dir / "out").string()) + " --verbose");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("4 of 4 sides real"), std::string::npos) << r.output;
  const cv::Mat mask = cv::imread((dir / "out" / "mask.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(mask.empty());
  EXPECT_EQ(mask.type(), CV_8UC1);
  EXPECT_EQ(mask.size(), cv::Size(800, 600));
  EXPECT_FALSE(cv::imread((dir / "out" / "overlay.png").string()).empty());
  const CommandResult valid =
      RunCommand(Quote((SourceDir() / "scripts" / "validate-json").string()) + " " +
                 Quote((dir / "out" / "boundary.json").string()));
  EXPECT_EQ(valid.exit_code, 0) << valid.output;
}

TEST(SegmentBoundaryCli, OrientationIsAChoiceRecordedByName) {
  TempDir dir;
  const fs::path image = WriteScene(dir, true);
  const CommandResult r = RunCommand(Binary() + " --image " + Quote(image.string()) + " --out " +
                                     Quote((dir / "out").string()) + " --orientation geometry");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json doc = ReadJsonFile(dir / "out" / "boundary.json");
  EXPECT_EQ(doc.at("orientation").at("method"), "geometry");
  EXPECT_EQ(doc.at("producer").at("options").at("orientation"), "geometry");
  EXPECT_EQ(doc.at("producer").at("options").at("verbose"), false);
}

TEST(SegmentBoundaryCli, MissingImageIsBadInput) {
  TempDir dir;
  const CommandResult r = RunCommand(Binary() + " --image " + Quote((dir / "nope.png").string()) +
                                     " --out " + Quote((dir / "out").string()));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("nope.png"), std::string::npos) << r.output;
  EXPECT_TRUE(Empty(dir / "out"));
}

TEST(SegmentBoundaryCli, UnreadableImageIsBadInput) {
  TempDir dir;
  std::ofstream(dir / "broken.png") << "this is not a PNG";
  const CommandResult r = RunCommand(Binary() + " --image " + Quote((dir / "broken.png").string()) +
                                     " --out " + Quote((dir / "out").string()));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("broken.png"), std::string::npos) << r.output;
  EXPECT_TRUE(Empty(dir / "out"));
}

TEST(SegmentBoundaryCli, EmptyTableIsBadInputWithoutOutputs) {
  TempDir dir;
  const fs::path image = WriteScene(dir, false);
  const CommandResult r = RunCommand(Binary() + " --image " + Quote(image.string()) + " --out " +
                                     Quote((dir / "out").string()));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("table.png"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no document found"), std::string::npos) << r.output;
  EXPECT_TRUE(Empty(dir / "out"));
}

TEST(SegmentBoundaryCli, HelpAndBadFlags) {
  EXPECT_EQ(RunCommand(Binary() + " --help").exit_code, 0);
  TempDir dir;
  const fs::path image = WriteScene(dir, true);
  EXPECT_EQ(RunCommand(Binary() + " --image " + Quote(image.string()) + " --out " +
                       Quote((dir / "out").string()) + " --orientation sideways")
                .exit_code,
            2);
}

// cameras.json naming `images` (800x600 each) with the first as reference.
fs::path WriteCameras(const TempDir& dir, const std::vector<std::string>& images, int width) {
  std::string views;
  for (const auto& name : images) {
    if (!views.empty()) views += ",";
    views += "{\"image\":\"" + name + "\",\"width\":" + std::to_string(width) +
             ",\"height\":600,\"K\":[[700,0,400],[0,700,300],[0,0,1]],"
             "\"R\":[[1,0,0],[0,1,0],[0,0,1]],\"t\":[0,0,0]}";
  }
  const fs::path path = dir / "cameras.json";
  std::ofstream(path) << "{\"format\":\"docunfold.cameras\",\"version\":1,\"reference\":\"" +
                             images[0] + "\",\"views\":[" + views + "]}";
  return path;
}

TEST(SegmentBoundaryCli, OtherViewsGetTheirOwnPageMasks) {
  TempDir dir;
  WriteScene(dir, true);
  WriteScene(dir, false);
  fs::copy_file(dir / "page.png", dir / "again.png");
  const fs::path cameras = WriteCameras(dir, {"page.png", "again.png", "table.png"}, 800);
  const std::string base = Binary() + " --image " + Quote((dir / "page.png").string()) + " --out " +
                           Quote((dir / "out").string());
  const CommandResult r = RunCommand(base + " --views " + Quote(dir.path().string()) +
                                     " --cameras " + Quote(cameras.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The reference's own outputs as always; a view without a page is left out.
  EXPECT_TRUE(fs::is_regular_file(dir / "out" / "mask.png"));
  EXPECT_FALSE(fs::exists(dir / "out" / "views" / "page"));
  const cv::Mat mask =
      cv::imread((dir / "out" / "views" / "again" / "mask.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(mask.empty());
  EXPECT_EQ(mask.size(), cv::Size(800, 600));
  EXPECT_GT(cv::countNonZero(mask), 0.15 * mask.total());
  EXPECT_TRUE(fs::is_regular_file(dir / "out" / "views" / "again" / "boundary.json"));
  // Every boundary.json records the options the stage ran with, the same.
  const Json reference_options =
      ReadJsonFile(dir / "out" / "boundary.json").at("producer").at("options");
  EXPECT_EQ(reference_options.at("orientation"), "auto");
  EXPECT_EQ(reference_options.at("work_size"), 640);
  EXPECT_FALSE(reference_options.contains("views"));  // paths are not recorded
  EXPECT_EQ(
      ReadJsonFile(dir / "out" / "views" / "again" / "boundary.json").at("producer").at("options"),
      reference_options);
  EXPECT_FALSE(fs::exists(dir / "out" / "views" / "table"));
  EXPECT_NE(r.output.find("table.png"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("page found in 1 of 2 other views"), std::string::npos) << r.output;

  // --views needs --cameras; a photo that is not the size cameras.json says
  // is bad input, named.
  EXPECT_EQ(RunCommand(base + " --views " + Quote(dir.path().string())).exit_code, 2);
  const fs::path wrong = WriteCameras(dir, {"page.png", "again.png"}, 640);
  const CommandResult bad = RunCommand(base + " --views " + Quote(dir.path().string()) +
                                       " --cameras " + Quote(wrong.string()));
  EXPECT_EQ(bad.exit_code, 3) << bad.output;
  EXPECT_NE(bad.output.find("again.png"), std::string::npos) << bad.output;
  // ... and writes nothing: the earlier run's files are still there.
  EXPECT_TRUE(fs::is_regular_file(dir / "out" / "views" / "again" / "mask.png"));
  // Without --views, the views of an earlier run go (they belong to it).
  ASSERT_EQ(RunCommand(base).exit_code, 0);
  EXPECT_FALSE(fs::exists(dir / "out" / "views"));
}

}  // namespace
}  // namespace docunfold::testing
