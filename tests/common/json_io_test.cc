#include "common/json_io.h"

#include <gtest/gtest.h>

#include <fstream>

#include "common/camera.h"
#include "common/errors.h"
#include "tests/support/test_support.h"

namespace docunfold {
namespace {

using testing::ErrorOf;

TEST(JsonIo, ReportsFileAndPointer) {
  testing::TempDir dir;
  Json doc = MakeHeader("docunfold.cameras", 1, "test");
  doc["reference"] = "a.jpg";
  doc["views"] = Json::array({{{"image", "a.jpg"},
                               {"width", 10},
                               {"height", 10},
                               {"K", {{1, 0, 5}, {0, 1, 5}, {0, 0, 1}}},
                               {"R", {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
                               {"t", {0, 0, "x"}}}});
  WriteJsonAtomic(dir / "c.json", doc);
  std::string err = ErrorOf([&] { ReadCameras(dir / "c.json"); });
  EXPECT_NE(err.find("c.json:/views/0/t/2: expected a number"), std::string::npos) << err;

  doc["views"][0]["t"] = {0, 0, 1};
  doc["version"] = 7;
  WriteJsonAtomic(dir / "c.json", doc);
  err = ErrorOf([&] { ReadCameras(dir / "c.json"); });
  EXPECT_NE(err.find("c.json:/version: unsupported version 7"), std::string::npos) << err;

  doc["version"] = 1;
  WriteJsonAtomic(dir / "c.json", doc);
  CameraSet set = ReadCameras(dir / "c.json");
  EXPECT_EQ(set.reference, "a.jpg");
  EXPECT_EQ(set.views[0].t.z(), 1);
}

TEST(JsonIo, EmptyAndMalformedFiles) {
  testing::TempDir dir;
  { std::ofstream(dir / "empty.json"); }
  EXPECT_NE(ErrorOf([&] { ReadJsonFile(dir / "empty.json"); }).find("empty file"),
            std::string::npos);
  { std::ofstream(dir / "bad.json") << "{\"a\": "; }
  EXPECT_NE(ErrorOf([&] { ReadJsonFile(dir / "bad.json"); }).find("not valid JSON"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ReadJsonFile(dir / "none.json"); }).find("cannot open"),
            std::string::npos);
}

TEST(Camera, ProjectsAndCastsRays) {
  PinholeCamera c;
  c.K << 1000, 0, 320, 0, 1000, 240, 0, 0, 1;
  c.R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  c.t = {0.1, -0.2, 2};
  Eigen::Vector3d x(0.3, 0.1, 0.5);
  Eigen::Vector2d p = c.Project(x);
  Eigen::Vector3d d = c.RayDirection(p);
  Eigen::Vector3d to_x = (x - c.Center()).normalized();
  EXPECT_NEAR((d - to_x).norm(), 0, 1e-9);
}

}  // namespace
}  // namespace docunfold
