// Where a point of a point cloud came from: the `source` property of
// densify's points.ply, read by init-mesh, optimize and the report.
#pragma once

#include <cstdint>

namespace docunfold {

enum class PointSource : uint8_t {
  kSfm = 0,      // COLMAP's sparse points
  kTexture = 1,  // print followed by optical flow from the reference view
  kOutline = 2,  // the page's real sides matched along epipolar lines
  kStep = 3,     // shading steps of blank paper (a fold's crease)
  kSwept = 4,    // print found by sweeping depth along the reference's rays
};
constexpr int kPointSourceCount = 5;

}  // namespace docunfold
