// PLY meshes and point clouds, binary or ASCII, readable by MeshLab:
// float x,y,z; optional uchar red,green,blue; any number of extra per-vertex
// scalar properties (s, t, track_length, ...); polygon faces of any size.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace docunfold {

namespace fs = std::filesystem;

enum class PlyEncoding { kBinary, kAscii };
enum class PlyScalar { kFloat32, kFloat64, kInt32, kUint32, kUint8 };

struct PlyProperty {
  std::string name;
  PlyScalar type = PlyScalar::kFloat32;
  std::vector<double> values;  // one per vertex
};

struct PlyData {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<uint8_t, 3>> colors;  // empty, or one per vertex
  std::vector<PlyProperty> properties;         // extra per-vertex scalars
  std::vector<std::vector<int>> faces;         // vertex indices, any arity
  std::vector<std::string> comments;           // header comment lines

  const PlyProperty* FindProperty(const std::string& name) const;
  // Adds (or replaces) an extra per-vertex property.
  void SetProperty(const std::string& name, std::vector<double> values,
                   PlyScalar type = PlyScalar::kFloat32);
  // Value of a "comment <key> <value...>" line, if present.
  std::optional<std::string> CommentValue(const std::string& key) const;
  // Grid size from "comment grid NX NY" (vertices per row, rows).
  std::optional<std::array<int, 2>> GridSize() const;
  void SetGridSize(int nx, int ny);
};

// Writes atomically; throws OutputError. Checks that faces index vertices
// and that property sizes match (std::invalid_argument otherwise).
void WritePly(const fs::path& path, const PlyData& ply,
              PlyEncoding encoding = PlyEncoding::kBinary);

// Reads ASCII or binary (little/big endian) PLY; throws InputError naming the
// file and the problem (truncated data, NaN coordinates, bad indices, ...).
PlyData ReadPly(const fs::path& path);

}  // namespace docunfold
