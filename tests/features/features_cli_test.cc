// The detect-features command line: outputs and their format, and bad input
// (missing or unreadable image or mask, a mask of the wrong size, an empty
// mask) failing with exit 3, a message naming the file and no output.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

std::string Binary() { return Quote(StageBinary("detect-features").string()); }

struct Inputs {
  fs::path image, mask;
};

Inputs WriteInputs(const TempDir& dir) {
  cv::Mat3b image(600, 800, cv::Vec3b(80, 80, 80));
  cv::Mat1b mask = cv::Mat1b::zeros(image.size());
  mask(cv::Rect(100, 60, 600, 480)).setTo(255);
  image.setTo(cv::Scalar(240, 240, 240), mask);
  for (int y = 120; y < 400; y += 28)
    cv::putText(image, "Dolphins keep the happy fjord quality", {140, y}, cv::FONT_HERSHEY_COMPLEX,
                0.6, cv::Scalar(20, 20, 20), 1, cv::LINE_AA);
  cv::rectangle(image, cv::Rect(140, 460, 500, 2), cv::Scalar(30, 30, 30), cv::FILLED);
  Inputs in{dir / "reference.png", dir / "mask.png"};
  cv::imwrite(in.image.string(), image);
  cv::imwrite(in.mask.string(), mask);
  return in;
}

std::string Command(const fs::path& image, const fs::path& mask, const fs::path& out) {
  return Binary() + " --image " + Quote(image.string()) + " --mask " + Quote(mask.string()) +
         " --out " + Quote(out.string());
}

bool Empty(const fs::path& dir) {
  return !fs::exists(dir) || fs::directory_iterator(dir) == fs::directory_iterator();
}

TEST(DetectFeaturesCli, WritesFeaturesAndOverlay) {
  TempDir dir;
  const Inputs in = WriteInputs(dir);
  const CommandResult r = RunCommand(Command(in.image, in.mask, dir / "out") + " --verbose");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(cv::imread((dir / "out" / "overlay.png").string()).empty());
  const CommandResult valid =
      RunCommand(Quote((SourceDir() / "scripts" / "validate-json").string()) + " " +
                 Quote((dir / "out" / "features.json").string()));
  EXPECT_EQ(valid.exit_code, 0) << valid.output;
  std::ifstream f(dir / "out" / "features.json");
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"kind\": \"text\""), std::string::npos);
  EXPECT_NE(text.find("\"kind\": \"edge\""), std::string::npos);
}

TEST(DetectFeaturesCli, MissingOrUnreadableInputsAreBadInput) {
  TempDir dir;
  const Inputs in = WriteInputs(dir);
  std::ofstream(dir / "broken.png") << "not an image";
  for (const auto& [image, mask, name] :
       {std::tuple{dir / "nope.png", in.mask, std::string("nope.png")},
        std::tuple{in.image, dir / "nomask.png", std::string("nomask.png")},
        std::tuple{dir / "broken.png", in.mask, std::string("broken.png")},
        std::tuple{in.image, dir / "broken.png", std::string("broken.png")}}) {
    const CommandResult r = RunCommand(Command(image, mask, dir / "out"));
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
    EXPECT_TRUE(Empty(dir / "out"));
  }
}

TEST(DetectFeaturesCli, WrongSizeOrEmptyMaskIsBadInput) {
  TempDir dir;
  const Inputs in = WriteInputs(dir);
  cv::imwrite((dir / "small.png").string(), cv::Mat1b(300, 400, uchar(255)));
  cv::imwrite((dir / "empty.png").string(), cv::Mat1b::zeros(600, 800));
  for (const std::string name : {"small.png", "empty.png"}) {
    const CommandResult r = RunCommand(Command(in.image, dir / name, dir / "out"));
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
    EXPECT_TRUE(Empty(dir / "out"));
  }
}

TEST(DetectFeaturesCli, Help) { EXPECT_EQ(RunCommand(Binary() + " --help").exit_code, 0); }

}  // namespace
}  // namespace docunfold::testing
