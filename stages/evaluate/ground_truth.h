// Ground truth of a data set (ground_truth/: flat.png, page.json, mesh.ply,
// cameras.json, features.json) and what is derived from it to judge
// the pipeline: the true page region, corners, outline and straight lines as
// a camera sees them. evaluate's front-end figures and the accuracy tests of
// every stage share these.
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/ply.h"
#include "common/raster.h"

namespace docunfold::evaluate {

namespace fs = std::filesystem;

struct TrueLine {
  std::string kind;                     // text, rule or border
  std::vector<Eigen::Vector2d> points;  // flat.png pixels (image pixels once projected)
};

struct GroundTruth {
  fs::path root;       // data-set folder
  double width_m = 0;  // page size
  double height_m = 0;
  int flat_width = 0;  // flat.png size in pixels
  int flat_height = 0;
  CameraSet cameras;
  PlyData mesh;  // true surface, with s and t
  std::vector<Triangle> triangles;
  std::vector<TrueLine> lines;  // empty when features.json is absent

  double Diagonal() const { return std::hypot(width_m, height_m); }
  // Point of the true surface at flat.png pixel (x, y), if inside the page.
  std::optional<Eigen::Vector3d> SurfacePoint(const Eigen::Vector2d& flat_px) const;

  // The surface rasterized into `camera`'s image (face ids and depth),
  // kept for the last camera asked: the page mask, corners, outline and
  // lines of one view share it. Not for concurrent use.
  const RasterResult& ViewRaster(const PinholeCamera& camera) const;

  // Rasterization of the surface in (s, t) space, built on first use.
  mutable RasterResult st_raster_;
  mutable double st_scale_ = 0;
  mutable std::optional<PinholeCamera> view_camera_;
  mutable RasterResult view_raster_;
};

// True when `dataset` has what LoadGroundTruth needs (page.json,
// cameras.json, mesh.ply, flat.png under ground_truth/).
bool HasTrueSurface(const fs::path& dataset);

// Loads ground_truth/ of a data set. Throws InputError naming the file when
// something is missing or malformed.
GroundTruth LoadGroundTruth(const fs::path& dataset);

// Whether the print at flat.png pixel `flat_px` is seen by `camera`: on the
// page, in front of the camera, inside its image, not hidden by the page
// itself, and the printed side (not the blank back) facing the camera.
bool TruePointSeen(const GroundTruth& gt, const PinholeCamera& camera,
                   const Eigen::Vector2d& flat_px);

// True page region in the image of `camera` (255 inside).
cv::Mat1b TruePageMask(const GroundTruth& gt, const PinholeCamera& camera);

// The four page corners (top-left, top-right, bottom-right, bottom-left of
// flat.png) projected into `camera`'s image.
std::array<Eigen::Vector2d, 4> TrueCorners(const GroundTruth& gt, const PinholeCamera& camera);

// How a view shows each true corner (TrueCorners order): outside the image
// (or within `margin_px` of its border), visible, or hidden by the page
// itself (a flap folded over it).
enum class CornerView { kOutside, kVisible, kHidden };
std::array<CornerView, 4> TrueCornersInView(const GroundTruth& gt, const PinholeCamera& camera,
                                            double margin_px = 3.0);

// Mean length of the two diagonals of the true corners in the view.
double ProjectedDiagonal(const GroundTruth& gt, const PinholeCamera& camera);

// The page's outline (the border of flat.png carried by the true surface)
// projected into `camera`, about every `step_px` flat pixels; points outside
// the image or hidden by the page are left out, so it may be in pieces.
std::vector<std::vector<Eigen::Vector2d>> TrueOutlineInView(const GroundTruth& gt,
                                                            const PinholeCamera& camera,
                                                            double step_px = 2.0);

// True straight lines of the page (gt.lines) projected into `camera`, sampled
// about every `step_px` flat pixels; points hidden by the page itself,
// outside the image, or where the camera sees the page's blank back (a
// corner curled over) are dropped (a line may so split into pieces).
std::vector<TrueLine> TrueLinesInView(const GroundTruth& gt, const PinholeCamera& camera,
                                      double step_px = 2.0);

// True straight lines of a page read off its flat scan (ground_truth/flat.png)
// for data sets whose ground truth has no features.json (the independently
// rendered sets): text baselines (kind "text": the bottom edge of the
// characters that sit on it) and rules (kind "rule": centre lines of long
// thin dark lines), in flat.png pixels. The flat scan is undistorted and
// clean, so classical layout analysis is exact enough there; a test checks it
// against synth's own lines on every synth set that has both.
std::vector<TrueLine> LinesFromFlatScan(const GroundTruth& gt);

// The page's true lines: synth's (features.json), else read off flat.png.
std::vector<TrueLine> TruthLines(const GroundTruth& gt);

// Whether the page is a text page or a table, on which a detector must
// cover half the lines (kMinLineRecall, front_end.h); receipts and posters
// (short lines, few of them) are only measured. From synth.json's kind, else
// from the lines.
bool LineRecallRequired(const GroundTruth& gt);

}  // namespace docunfold::evaluate
