#include "common/page_files.h"

#include <gtest/gtest.h>

#include <fstream>

#include "common/errors.h"
#include "tests/support/test_support.h"

namespace docunfold {
namespace {

using testing::ErrorOf;

const char* kBoundary = R"({"format": "docunfold.boundary", "version": 1,
  "producer": {"stage": "test", "version": "0"}, "image": "r.png", "width": 100, "height": 80,
  "contour": [[10, 10], [90, 10], [90, 70], [10, 70]],
  "corners": [[10, 10], [90, 10], [90, 70], [10, 70]],
  "sides": {"top": {"points": [[10, 10], [90, 10]], "real": true},
            "right": {"points": [[90, 10], [90, 70]], "real": true},
            "bottom": {"points": [[10, 70], [90, 70]], "real": false},
            "left": {"points": [[10, 10], [10, 70]], "real": true}}})";

TEST(PageFiles, ReadsABoundary) {
  testing::TempDir dir;
  std::ofstream(dir / "b.json") << kBoundary;
  Boundary b = ReadBoundary(dir / "b.json");
  EXPECT_EQ(b.width, 100);
  EXPECT_EQ(b.RealSides(), 3);
  EXPECT_FALSE(b.sides[2].real);
  EXPECT_EQ(b.corners[2], Eigen::Vector2d(90, 70));
}

TEST(PageFiles, ProblemsNameFileAndPointer) {
  testing::TempDir dir;
  std::string broken = kBoundary;
  broken.replace(broken.find("\"real\": false"), 13, "\"real\": \"no\"");
  std::ofstream(dir / "b.json") << broken;
  EXPECT_NE(ErrorOf([&] { ReadBoundary(dir / "b.json"); }).find("b.json:/sides/bottom/real: "),
            std::string::npos);
  std::ofstream(dir / "f.json") << R"({"format": "docunfold.features", "version": 1, "segments": [
            {"kind": "text", "points": [[1, 2], [3, 4]]}, {"kind": "curve", "points": [[1, 2], [3, 4]]}]})";
  EXPECT_NE(ErrorOf([&] { ReadFeatures(dir / "f.json"); }).find("f.json:/segments/1/kind: "),
            std::string::npos);
  std::ofstream(dir / "g.json")
      << R"({"format": "docunfold.features", "version": 1, "segments": [{"kind": "edge", "points": [[1, 2]]}]})";
  EXPECT_NE(ErrorOf([&] { ReadFeatures(dir / "g.json"); }).find("g.json:/segments/0/points: "),
            std::string::npos);
  std::ofstream(dir / "h.json")
      << R"({"format": "docunfold.features", "version": 1, "segments": []})";
  EXPECT_TRUE(ReadFeatures(dir / "h.json").segments.empty());
}

}  // namespace
}  // namespace docunfold
