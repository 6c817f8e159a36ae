// segment-boundary: the document region in the reference image, its outline,
// its four corners and its four sides (the paper's reference image and
// document boundary). Sides that run along the image border, because the
// page is cut off there, are marked not real: they must never be straightened.
//
// Orientation convention (also in schemas/docunfold.boundary.schema.json):
// corners are TL, TR, BR, BL, in clockwise order as seen in the image. Which
// corner is TL comes from the text when the page has enough of it (the side
// the text lines' tops face is the top; `orientation.method` = "text"),
// otherwise from geometry (the side whose outward normal points most towards
// the image's top is the top; `orientation.method` = "geometry").
#pragma once

#include <array>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/json_io.h"
#include "common/option_table_fwd.h"

namespace docunfold::boundary {

namespace fs = std::filesystem;

// Where the page's top comes from.
enum class OrientationSource {
  kAuto,      // the text when the page has enough of it to tell, else geometry
  kText,      // the text; bad input when it does not tell
  kGeometry,  // the side facing the image's top
};

struct BoundaryOptions {
  // Long side, in pixels, of the downscaled image the region is found on
  // before its outline is refined at full resolution.
  int work_size = 640;
  // Width of the image frame used to learn the table's colour, as a fraction
  // of the image's short side.
  double frame_fraction = 0.04;
  // A pixel belongs to the table (or the table in shadow) while its
  // Mahalanobis distance to the table's colour is below this (in standard
  // deviations of the table's colour spread).
  double table_distance = 5.0;
  // Hysteresis: pixels between this distance and `table_distance` are page
  // where they touch the page found above and fill an area at least
  // `weak_min_width` work pixels wide. Paper in a fold's shadow can be as
  // dark as a textured table; the width keeps the table's own light specks
  // (at the outline, where they would pull a corner) out.
  double weak_table_distance = 3.0;
  int weak_min_width = 9;
  // The page must cover at least this fraction of the image.
  double min_area_fraction = 0.01;
  // Contour points closer than this to the image border (pixels) lie on the
  // border: the page is cut off there.
  double border_tolerance_px = 2.0;
  // A side counts as real when at most this fraction of its length lies on
  // the image border (a real corner may touch it).
  double max_cut_fraction = 0.02;
  // Douglas–Peucker tolerance of the stored contour and sides (pixels).
  double contour_epsilon_px = 0.7;
  OrientationSource orientation = OrientationSource::kAuto;
  // Log each step and its time on stderr.
  bool verbose = false;
};

// The other photos of the scene: when `views_dir` is given, the page is also
// found in every view that `cameras_path` (sfm's cameras.json) registers but
// the reference.
struct OtherViews {
  fs::path views_dir;     // folder of the photos; empty: none
  fs::path cameras_path;  // cameras.json, given with views_dir
};

// Declares every field of `options`, and --views/--cameras into `views`, as
// flags of `table` (see common/option_table.h); a field's value is its
// default.
void DeclareOptions(OptionTable& table, BoundaryOptions* options, OtherViews* views);

// One side of the page: a polyline along the outline from one corner to the
// next, and which parts of it are the true page edge.
struct Side {
  std::vector<cv::Point2d> points;
  // The whole side is page edge, not cut by the image border. A side run on
  // past a folded corner's fold to the corner counts as page edge all along.
  bool real = true;
  // Pieces of `points` that are page edge; all of it when `real`.
  std::vector<std::vector<cv::Point2d>> real_parts;
  double cut_fraction = 0;  // fraction of its length on the image border
};

// A page corner folded over or under the page: the outline runs along the
// fold from `fold[0]` (where corner finding put the corner) to `fold[1]`,
// and the corner is placed where the two sides' lines meet past it.
struct FoldedCorner {
  int corner = 0;  // index into BoundaryResult::corners
  std::array<cv::Point2d, 2> fold;
};

enum SideIndex { kTop = 0, kRight = 1, kBottom = 2, kLeft = 3 };
constexpr const char* kSideNames[4] = {"top", "right", "bottom", "left"};
constexpr const char* kCornerNames[4] = {"TL", "TR", "BR", "BL"};

struct Orientation {
  std::string method;     // "text" or "geometry"
  double confidence = 0;  // text: fraction of votes for the chosen top
  int votes = 0;          // text: characters that voted
};

struct BoundaryResult {
  cv::Mat1b mask;                      // 255 = page, image size
  std::vector<cv::Point2d> contour;    // closed, clockwise in the image
  std::array<cv::Point2d, 4> corners;  // TL, TR, BR, BL
  // False where the "corner" is where the outline meets the image border
  // (the page's true corner is outside the image).
  std::array<bool, 4> corner_in_image{{true, true, true, true}};
  // top: TL->TR, right: TR->BR, bottom: BL->BR, left: TL->BL.
  std::array<Side, 4> sides;
  std::vector<FoldedCorner> folded_corners;
  Orientation orientation;
  double area_fraction = 0;  // page area / image area
};

// Finds the page. Throws InputError("no document found: ...") when there is
// no page-like region (an empty table, a blank image).
BoundaryResult SegmentBoundary(const cv::Mat& bgr_image, const BoundaryOptions& options);

// boundary.json (format docunfold.boundary, version 1); `options_record`
// goes into its producer record (OptionTable::Record).
Json BoundaryToJson(const BoundaryResult& result, const std::string& image_name, int width,
                    int height, const Json& options_record);

// The reference image with the outline, corners and side names drawn: real
// sides in green, cut sides dashed in red; at most `max_size` pixels long.
cv::Mat DrawBoundaryOverlay(const cv::Mat& bgr_image, const BoundaryResult& result,
                            int max_size = 1600);

// What the stage writes for one photo into `dir`: mask.png, overlay.png and
// boundary.json.
struct BoundaryFiles {
  fs::path dir;
  cv::Mat1b mask;
  cv::Mat overlay;
  Json doc;
};

// The page in every view of `views` but the reference, each for
// <out_dir>/views/<photo name>/. A view without a page is logged and left
// out (render uses whichever views it finds); a photo that is missing or not
// the size cameras.json says fails. `tried` receives how many views were
// tried.
std::vector<BoundaryFiles> SegmentOtherViews(const OtherViews& views, const fs::path& out_dir,
                                             const BoundaryOptions& options,
                                             const Json& options_record, int* tried);

// Writes `reference` (into its dir, the output directory), removes the views
// of an earlier run from <dir>/views (they would no longer match), then
// writes `views`.
void WriteBoundaryFiles(const BoundaryFiles& reference, const std::vector<BoundaryFiles>& views);

// Internals exposed for tests.
namespace detail {
// Turning angle (radians, positive = convex for a clockwise outline) at each
// point between the chords to the points `reach` steps before and after.
std::vector<double> TurningAngles(const std::vector<cv::Point>& contour, int reach);
// Indices (into the clockwise `contour`) of the four corners, in contour
// order: the four sharpest convex turns of the outline (page corners turn by
// 60-120 degrees, folds far less); the largest quadrilateral on the convex
// hull when there are not four turns.
// `is_fold(a, b)`, when given, says whether the straight line between two
// outline points is a fold across the page: candidates joined by a fold are
// kinks where the fold meets a side, not corners, and are passed over while
// four other candidates remain.
using FoldTest = std::function<bool(const cv::Point&, const cv::Point&)>;
std::array<int, 4> FindCornerIndices(const std::vector<cv::Point>& contour,
                                     const FoldTest& is_fold = nullptr);
// Whether the segment a-b (full-resolution pixels) runs inside the page and
// separates two differently shaded parts of it along most of its length, as
// a fold does (text is blurred away first). `grey` is the page image at
// `scale` work pixels per full pixel; `mask` the page region at that size.
// `offset_px` (work pixels) is how far either side of the segment the two
// panels are sampled; 0: 2 % of its length, at least 4.
bool IsShadingStep(const cv::Mat1f& grey, const cv::Mat1b& mask, double scale, const cv::Point& a,
                   const cv::Point& b, double offset_px = 0);
// Where a corner in the image is the end of a fold's crease that meets a
// side a short way from the page's corner, moves the corner there: with the
// narrow panel beyond the crease seen foreshortened, the crease's end turns
// the outline more than the corner does. It moves when, at a quarter of the
// corner reach, exactly one of its arms turns by `min_turn_deg` or more
// within `max_arm_fraction` of the arm, by less than the corner found turns,
// which turns by under 60 degrees (a page corner turns more); and when
// `is_fold` joins the corner found, but not that turn, to an outline point at
// least an eighth of the outline away (else the corner found may be the
// page's and the turn the crease's end). See docs/decisions/segment-boundary.md,
// "Corners beside a crease's end and where the page leaves the image".
std::array<int, 4> MoveFoldEndsToPageCorners(const std::vector<cv::Point>& contour,
                                             std::array<int, 4> idx,
                                             const std::function<bool(const cv::Point&)>& on_border,
                                             const FoldTest& is_fold, double min_turn_deg = 20,
                                             double max_arm_fraction = 0.15);
// Where a corner is the point at which the outline meets the image border
// (the page runs out of the image there), moves it to a sharp convex turn
// (>= `min_turn_deg`) on its real arm within `max_arm_fraction` of that
// arm's length, when there is one: the page's own corner, with the short
// piece from it to the border belonging to the next, cut side (the border
// exit can turn more sharply than the true corner). Taking a crease kink
// there instead costs little: the piece joins a cut side, which is never
// straightened, while a real side running on past its corner would be
// straightened through it. See docs/decisions/segment-boundary.md, "Corners
// beside a crease's end and where the page leaves the image".
// `on_border` says whether an outline point lies on the image border.
std::array<int, 4> MoveBorderCornersToPageCorners(
    const std::vector<cv::Point>& contour, std::array<int, 4> idx,
    const std::function<bool(const cv::Point&)>& on_border, double min_turn_deg = 20,
    double max_arm_fraction = 0.25);
// Sharpens a corner found on the outline: the intersection of straight lines
// fitted to the outline just before and just after it (a corner the mask
// rounds off, or a ragged outline, moves the point of sharpest turn away).
// Returns the outline point itself when the fits disagree with it.
cv::Point2d RefineCorner(const std::vector<cv::Point>& contour, int index, int reach);
// Rotates corner order so that the side whose outward normal points most
// towards image-up is the top; corners must be clockwise.
int GeometricTopSide(const std::array<cv::Point2d, 4>& corners);
}  // namespace detail

}  // namespace docunfold::boundary
