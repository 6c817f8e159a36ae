// Ground truth of a data set (DESIGN §3) and what tests derive from it: the
// true page region, corners and straight lines as seen by a camera.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "common/camera.h"
#include "common/ply.h"
#include "common/raster.h"

namespace docunfold::testing {

namespace fs = std::filesystem;

struct TrueLine {
  std::string kind;                     // text, rule or border
  std::vector<Eigen::Vector2d> points;  // flat.png pixels
};

struct GroundTruth {
  fs::path root;          // data-set folder
  double width_m = 0;     // page size
  double height_m = 0;
  int flat_width = 0;     // flat.png size in pixels
  int flat_height = 0;
  CameraSet cameras;
  PlyData mesh;           // true surface, with s and t
  std::vector<Triangle> triangles;
  std::vector<TrueLine> lines;  // empty when features.json is absent

  double Diagonal() const { return std::hypot(width_m, height_m); }
  // Point of the true surface at flat.png pixel (x, y), if inside the page.
  std::optional<Eigen::Vector3d> SurfacePoint(const Eigen::Vector2d& flat_px) const;

  // Rasterization of the surface in (s, t) space, built on first use.
  mutable RasterResult st_raster_;
  mutable double st_scale_ = 0;
};

// Loads ground_truth/ of a data set; fails the current test (and returns
// nullopt) when something is missing.
std::optional<GroundTruth> LoadGroundTruth(const fs::path& dataset);

// True page region in the image of `camera` (255 inside).
cv::Mat1b TruePageMask(const GroundTruth& gt, const PinholeCamera& camera);

// The four page corners (top-left, top-right, bottom-right, bottom-left of
// flat.png) projected into `camera`'s image.
std::array<Eigen::Vector2d, 4> TrueCorners(const GroundTruth& gt,
                                           const PinholeCamera& camera);

// True straight lines of the page projected into `camera`, sampled about
// every `step_px` flat pixels; points hidden by the page itself or outside the
// image are dropped (a line may so split into several pieces).
std::vector<TrueLine> TrueLinesInView(const GroundTruth& gt,
                                      const PinholeCamera& camera,
                                      double step_px = 2.0);

}  // namespace docunfold::testing
