#include "common/gltf.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/test_support.h"

namespace docunfold {
namespace {

TEST(Gltf, WritesABinaryGltfWithTexture) {
  testing::TempDir dir;
  GltfMesh m;
  m.positions = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  m.texcoords = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.triangles = Triangulate({{0, 1, 2, 3}});
  m.texture = cv::Mat(8, 8, CV_8UC3, cv::Scalar(0, 128, 255));
  WriteGlb(dir / "m.glb", {m});
  std::ifstream f(dir / "m.glb", std::ios::binary);
  char magic[4];
  f.read(magic, 4);
  EXPECT_EQ(std::string(magic, 4), "glTF");
  EXPECT_GT(fs::file_size(dir / "m.glb"), 200u);
}

// The JSON chunk of a .glb file (header, then the first chunk).
nlohmann::json GlbJson(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  char header[12];
  f.read(header, 12);
  uint32_t length = 0, type = 0;
  f.read(reinterpret_cast<char*>(&length), 4);
  f.read(reinterpret_cast<char*>(&type), 4);
  std::string json(length, ' ');
  f.read(json.data(), length);
  return nlohmann::json::parse(json);
}

TEST(Gltf, PointCloudsBecomePointPrimitivesWithColours) {
  testing::TempDir dir;
  GltfMesh m;
  m.positions = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}};
  m.triangles = {{0, 1, 2}};
  GltfPoints p;
  p.positions = {{0, 0, 2}, {0.5, 0.5, 2}};
  p.colors = {{1, 0, 0}, {0, 1, 0}};
  WriteGlb(dir / "s.glb", {m}, {p});
  const auto j = GlbJson(dir / "s.glb");
  ASSERT_EQ(j["meshes"].size(), 2u);
  EXPECT_EQ(j["meshes"][1]["primitives"][0]["mode"], 0);  // POINTS
  EXPECT_TRUE(j["meshes"][1]["primitives"][0]["attributes"].contains("COLOR_0"));
  EXPECT_EQ(j["scenes"][0]["nodes"].size(), 2u);
  // OpenCV axes become glTF's: y and z flip.
  const int acc = j["meshes"][1]["primitives"][0]["attributes"]["POSITION"];
  EXPECT_DOUBLE_EQ(j["accessors"][acc]["max"][2].get<double>(), -2.0);
}

}  // namespace
}  // namespace docunfold
