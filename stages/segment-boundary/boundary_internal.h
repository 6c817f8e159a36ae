// The steps of segment-boundary and what they hand each other (internal to
// the stage): the page region (page_region.cc), the outline and its corners
// (corners.cc), its sides (sides.cc).
#pragma once

#include <array>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "stages/segment-boundary/segment_boundary.h"

namespace docunfold::boundary::internal {

// Logs one step (with the seconds since the stage began) when verbose.
using StepLog = std::function<void(const std::string&)>;

// Whether an outline point (full-resolution pixels) lies on the image border.
using BorderTest = std::function<bool(const cv::Point&)>;

// Points within `tolerance` pixels of the border of an image of `size`.
BorderTest OnImageBorder(cv::Size size, double tolerance);

// --- Page region (page_region.cc) -------------------------------------------

// The page found on the image downscaled to the work size.
struct CoarseRegion {
  cv::Mat3b small;     // the image at the work size (a copy when not smaller)
  double scale = 1.0;  // work pixels per full-resolution pixel, <= 1
  cv::Mat1b coarse;    // 255 = page, at the work size
};

// Step 1: everything that is not table, on the downscaled image. Throws
// InputError("no document found: ...") when the frame has no dominant
// colour or no region is large enough.
CoarseRegion FindCoarseRegion(const cv::Mat3b& full, const BoundaryOptions& options,
                              const StepLog& step);

// Step 2: the region's outline refined at full resolution and smoothed; the
// largest region, holes filled.
cv::Mat1b RefinePageMask(const cv::Mat3b& full, const CoarseRegion& region);

// --- Outline and corners (corners.cc) ---------------------------------------

// The area enclosed by the closed outline `c`, positive when it runs
// clockwise in the image.
double SignedArea(const std::vector<cv::Point>& c);

// Outline points on either side of a point over which its turning is
// measured, and its corner's sides fitted: a few percent of the outline.
int CornerReach(size_t outline_points);

// What tells a fold across the page from a side: the page image at the work
// size, blurred so that text goes and the panels' shading stays, and the page
// region at that size.
struct ShadingImage {
  cv::Mat1f grey;
  cv::Mat1b mask;
  double scale = 1.0;  // work pixels per full-resolution pixel
};
ShadingImage MakeShadingImage(const cv::Mat3b& small, const cv::Mat1b& mask, int full_width);

// Step 3: indices into the clockwise `contour` of the four corners, in
// contour order (not yet rotated to put the top first).
std::array<int, 4> FindCorners(const std::vector<cv::Point>& contour, const ShadingImage& shading,
                               const BorderTest& on_border);

// --- Outline and sides (sides.cc) -------------------------------------------

// The outline of `mask`'s largest region, clockwise in the image. Throws
// InputError when there is none.
std::vector<cv::Point> ClockwiseOutline(const cv::Mat1b& mask);

std::vector<cv::Point2d> ToDouble(const std::vector<cv::Point>& pts);

// The length of the open polyline `p` (pixels).
double PolylineLength(const std::vector<cv::Point2d>& p);

// The parameter s at which the line a + s da meets the line b + t db (unit
// directions); nullopt when they cross at an angle whose sine is below
// `min_sine` (nearly parallel).
std::optional<double> LineMeeting(const cv::Point2d& a, const cv::Point2d& da, const cv::Point2d& b,
                                  const cv::Point2d& db, double min_sine);

// Douglas-Peucker simplification with tolerance `eps` (pixels).
std::vector<cv::Point2d> Simplify(const std::vector<cv::Point2d>& pts, double eps, bool closed);

// Side `i` (kTop...) along the clockwise `contour` from corner idx[i] to
// idx[i + 1], stored in the schema's direction, ending at the sharpened
// `corners`, with the parts of it that are page edge.
Side TraceSide(const std::vector<cv::Point>& contour, const std::array<int, 4>& idx, int i,
               const std::array<cv::Point2d, 4>& corners, const BorderTest& on_border,
               const BoundaryOptions& options);

// --- Folded corners (folded_corners.cc) --------------------------------------

// Step 5: where a corner of the page is folded over or under it (a dog-ear),
// the outline has a straight fold between two sides, and the corner found is
// one end of the fold. Moves such corners to where the two sides' lines meet
// past the fold (a point of the image that is not page), runs both sides on
// to it (they stay real: page edge, straight), and returns the folds.
// A corner counts as folded when the fold (at least 6.5 % of the outline)
// and the side past it are straight, each end of the fold turns by 20-70
// degrees, the corner they make turns by 50-130 degrees, and at most a fifth
// of the triangle cut off is page. A shading step running from either end
// of the fold across the page to the outline makes it a crease meeting a
// side instead. Reads result->mask; sides simplified to `epsilon_px`.
std::vector<FoldedCorner> CompleteFoldedCorners(const std::vector<cv::Point>& contour,
                                                const ShadingImage& shading,
                                                const BorderTest& on_border, double epsilon_px,
                                                BoundaryResult* result);

}  // namespace docunfold::boundary::internal
