#include "common/ply.h"

#include <gtest/gtest.h>

#include <fstream>

#include "common/errors.h"
#include "tests/support/test_support.h"

namespace docunfold {
namespace {

PlyData MakeGrid() {
  PlyData ply;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) ply.vertices.push_back({x * 0.5, y * 0.25, 0.1 * x * y});
  std::vector<double> s, t;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      s.push_back(x / 3.0);
      t.push_back(y / 2.0);
    }
  ply.SetProperty("s", s);
  ply.SetProperty("t", t);
  ply.SetProperty("track_length", std::vector<double>(12, 7), PlyScalar::kInt32);
  for (int i = 0; i < 12; ++i) ply.colors.push_back({uint8_t(i), 2, 250});
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x)
      ply.faces.push_back({y * 4 + x, y * 4 + x + 1, (y + 1) * 4 + x + 1, (y + 1) * 4 + x});
  ply.comments.push_back("TextureFile reference.png");
  ply.SetGridSize(4, 3);
  return ply;
}

class PlyRoundTrip : public ::testing::TestWithParam<PlyEncoding> {};

TEST_P(PlyRoundTrip, KeepsEverything) {
  testing::TempDir dir;
  PlyData in = MakeGrid();
  WritePly(dir / "m.ply", in, GetParam());
  PlyData out = ReadPly(dir / "m.ply");
  ASSERT_EQ(out.vertices.size(), in.vertices.size());
  for (size_t i = 0; i < in.vertices.size(); ++i)
    EXPECT_NEAR((out.vertices[i] - in.vertices[i]).norm(), 0, 1e-6);
  ASSERT_EQ(out.colors.size(), 12u);
  EXPECT_EQ(out.colors[5][0], 5);
  EXPECT_EQ(out.colors[5][2], 250);
  ASSERT_NE(out.FindProperty("s"), nullptr);
  EXPECT_NEAR(out.FindProperty("s")->values[2], 2 / 3.0, 1e-6);
  EXPECT_EQ(out.FindProperty("track_length")->values[3], 7);
  EXPECT_EQ(out.faces, in.faces);
  ASSERT_TRUE(out.GridSize());
  EXPECT_EQ((*out.GridSize())[0], 4);
  EXPECT_EQ(out.CommentValue("TextureFile").value_or(""), "reference.png");
}

INSTANTIATE_TEST_SUITE_P(Encodings, PlyRoundTrip,
                         ::testing::Values(PlyEncoding::kBinary, PlyEncoding::kAscii));

void WriteFile(const std::filesystem::path& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary);
  f << text;
}

TEST(PlyRead, RejectsAwkwardFiles) {
  testing::TempDir dir;
  WriteFile(dir / "empty.ply", "");
  EXPECT_THROW(ReadPly(dir / "empty.ply"), InputError);
  EXPECT_THROW(ReadPly(dir / "missing.ply"), InputError);
  WriteFile(dir / "nan.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
            "property float y\nproperty float z\nend_header\nnan 0 0\n");
  try {
    ReadPly(dir / "nan.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nan.ply: vertex 0"), std::string::npos);
  }
  WriteFile(dir / "trunc.ply",
            "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
            "property float x\nproperty float y\nproperty float z\nend_header\n"
            "abcdefgh");
  EXPECT_THROW(ReadPly(dir / "trunc.ply"), InputError);
  WriteFile(dir / "badface.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
            "property float y\nproperty float z\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n0 0 0\n3 0 1 2\n");
  EXPECT_THROW(ReadPly(dir / "badface.ply"), InputError);
}

// Inputs the fuzzer (fuzz/ply_fuzzer.cc) made, or ones like them: each is a
// clean InputError naming the file and the problem, not undefined behaviour.
void ExpectInputError(const std::filesystem::path& file, const std::string& problem) {
  try {
    ReadPly(file);
    ADD_FAILURE() << file << ": read without error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string() + ": " + problem), std::string::npos)
        << e.what();
  }
}

const char* const kAsciiVertexHeader =
    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
    "property float z\n";

TEST(PlyRead, RejectsAPropertyDeclaredTwice) {
  testing::TempDir dir;
  // The second x left the first one's value no place among the extras.
  WriteFile(dir / "twice.ply", std::string(kAsciiVertexHeader) +
                                   "property float s\nproperty float x\nend_header\n1 2 3 4 5\n");
  ExpectInputError(dir / "twice.ply", "vertex property 'x' declared twice");
}

TEST(PlyRead, RejectsValuesWithNoIntegerToBecome) {
  testing::TempDir dir;
  const std::string header = kAsciiVertexHeader;
  WriteFile(dir / "colour.ply", header +
                                    "property float red\nproperty float green\n"
                                    "property float blue\nend_header\n0 0 0 300 0 0\n");
  ExpectInputError(dir / "colour.ply", "vertex 0 has a colour outside 0..255");
  WriteFile(dir / "index.ply", header +
                                   "element face 1\nproperty list uchar float vertex_indices\n"
                                   "end_header\n0 0 0\n3 0 nan 1e30\n");
  ExpectInputError(dir / "index.ply", "face 0 indexes a missing vertex nan");
  WriteFile(dir / "list.ply",
            header + "property list float uchar extra\nend_header\n0 0 0 nan 1\n");
  ExpectInputError(dir / "list.ply", "bad list length in element vertex");
}

TEST(PlyRead, RejectsCountsTheFileCannotHold) {
  testing::TempDir dir;
  // Declared counts were allocated before the data ran out.
  WriteFile(dir / "count.ply",
            "ply\nformat binary_little_endian 1.0\nelement vertex 99999999999999\n"
            "property float x\nproperty float y\nproperty float z\nend_header\n0123456789ab");
  ExpectInputError(dir / "count.ply", "element vertex declares 99999999999999 items");
  WriteFile(dir / "empty.ply", std::string(kAsciiVertexHeader) +
                                   "element nothing 999999999999999999\nend_header\n0 0 0\n");
  EXPECT_EQ(ReadPly(dir / "empty.ply").vertices.size(), 1u);
}

TEST(PlyRead, ReadsDoubleAndBigEndianFromOtherTools) {
  testing::TempDir dir;
  std::string body =
      "ply\nformat binary_big_endian 1.0\nelement vertex 1\n"
      "property double x\nproperty double y\nproperty double z\n"
      "end_header\n";
  auto put_be = [&body](double d) {
    unsigned char b[8];
    std::memcpy(b, &d, 8);
    for (int i = 7; i >= 0; --i) body.push_back(char(b[i]));
  };
  put_be(1.5);
  put_be(-2.0);
  put_be(3.25);
  WriteFile(dir / "be.ply", body);
  PlyData p = ReadPly(dir / "be.ply");
  ASSERT_EQ(p.vertices.size(), 1u);
  EXPECT_EQ(p.vertices[0], Eigen::Vector3d(1.5, -2.0, 3.25));
}

}  // namespace
}  // namespace docunfold
