// Readers of the files that describe the page in the reference image, shared
// by every stage that uses them: 20_boundary/boundary.json
// (docunfold.boundary) and 30_features/features.json (docunfold.features).
// Both report problems as "file:/json/pointer: problem" (InputError).
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace docunfold {

namespace fs = std::filesystem;

inline const char* const kSideNames[4] = {"top", "right", "bottom", "left"};

struct BoundarySide {
  std::vector<Eigen::Vector2d> points;  // reference-image pixels
  bool real = false;  // false where the page is cut off by the image border
};

struct Boundary {
  fs::path file;
  int width = 0;  // size of the image the boundary was found in
  int height = 0;
  std::vector<Eigen::Vector2d> contour;     // closed outline
  std::array<Eigen::Vector2d, 4> corners;  // TL TR BR BL
  std::array<BoundarySide, 4> sides;       // top, right, bottom, left
  int RealSides() const;
};

Boundary ReadBoundary(const fs::path& file);

struct FeatureSegment {
  std::string kind;                     // "text" or "edge"
  std::vector<Eigen::Vector2d> points;  // reference-image pixels, >= 2
};

struct FeatureFile {
  fs::path file;
  std::string producer;  // the stage or program that wrote it ("" if unknown)
  int width = 0;         // image size the segments refer to (0: not given)
  int height = 0;
  std::vector<FeatureSegment> segments;
};

// Any detector's file: only format, version and segments[].kind/points are
// required (schemas/docunfold.features.schema.json).
FeatureFile ReadFeatures(const fs::path& file);

}  // namespace docunfold
