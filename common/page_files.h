// Readers of the files that describe the page in the reference image, shared
// by every stage that uses them: 20_boundary/boundary.json
// (docunfold.boundary) and 30_features/features.json (docunfold.features).
// Both report problems as "file:/json/pointer: problem" (InputError).
// Also: which 3D points belong to the document region of the reference view.
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/json_io.h"

namespace docunfold {

namespace fs = std::filesystem;

inline const char* const kSideNames[4] = {"top", "right", "bottom", "left"};

struct BoundarySide {
  std::vector<Eigen::Vector2d> points;  // reference-image pixels
  bool real = false;                    // false where the page is cut off by the image border
  // Pieces of `points` that are page edge: all of it when real; those of a
  // cut side when the file lists them (real_parts), else none.
  std::vector<std::vector<Eigen::Vector2d>> real_parts;
};

struct Boundary {
  fs::path file;
  int width = 0;  // size of the image the boundary was found in
  int height = 0;
  std::vector<Eigen::Vector2d> contour;    // closed outline
  std::array<Eigen::Vector2d, 4> corners;  // TL TR BR BL
  std::array<BoundarySide, 4> sides;       // top, right, bottom, left
  // Corners folded over or under the page: each the triangle of the image
  // between the page's corner and the fold's two ends, which shows no page.
  std::vector<std::array<Eigen::Vector2d, 3>> folded_away;
  int RealSides() const;
};

Boundary ReadBoundary(const fs::path& file);
// The same from a parsed document; `file` names it in errors.
Boundary ParseBoundary(const Json& doc, const fs::path& file);

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
  // Optional: unit vector in the image towards the text's baselines (the
  // reader's down), when the detector could tell.
  std::optional<Eigen::Vector2d> text_down;
};

// Any detector's file: only format, version and segments[].kind/points are
// required (schemas/docunfold.features.schema.json).
FeatureFile ReadFeatures(const fs::path& file);

// 20_boundary/mask.png as the document region (non-zero = page). Throws
// InputError naming the file when it is not width x height or is empty.
cv::Mat1b ReadDocumentMask(const fs::path& path, int width, int height);

// The page in a photo other than the reference, as segment-boundary found
// it: <boundary dir>/views/<photo stem>/mask.png, of the original photo (not
// undistorted; `distortion` is its lens's, OpenCV k1 k2 p1 p2).
struct ViewPage {
  PinholeCamera camera;
  std::array<double, 4> distortion{};
  cv::Mat1b mask;  // non-zero = page, camera.width x camera.height
  fs::path file;
};

// Every view of `cameras` (read from `cameras_file`, which gives the
// distortions) but its reference that has such a mask, in the file's order;
// InputError naming the file for a damaged one.
std::vector<ViewPage> ReadOtherViewPages(const CameraSet& cameras, const fs::path& cameras_file,
                                         const fs::path& boundary_dir);

// The document region in the reference image: `region` (e.g. mask.png, any
// non-zero pixel inside) grown by `margin_px`, so points on the page's very
// edge still count.
cv::Mat1b GrowRegion(const cv::Mat1b& region, double margin_px);

// The filled closed contour of `boundary`, grown by `margin_px`.
cv::Mat1b ContourRegion(const Boundary& boundary, double margin_px);

// Indices of the points in front of `camera` whose projection falls on a
// non-zero pixel of `region` (same size as the camera's image). Points of
// the table or background next to the page would otherwise count as page.
std::vector<int> PointsInRegion(const std::vector<Eigen::Vector3d>& points,
                                const PinholeCamera& camera, const cv::Mat1b& region);

}  // namespace docunfold
