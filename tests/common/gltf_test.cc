#include "common/gltf.h"

#include <fstream>
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace docunfold
