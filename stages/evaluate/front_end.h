// The pipeline's front end against the ground truth, in the reference view:
// segment-boundary's page region, corners and sides, and detect-features'
// segments (precision and recall against the page's true straight lines).
// `evaluate --front-end` writes these figures for a work directory; the
// accuracy tests of both stages assert them view by view.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "common/camera.h"
#include "common/json_io.h"
#include "common/page_files.h"
#include "stages/evaluate/ground_truth.h"

namespace docunfold::evaluate {

// What the front end must reach in the reference view (the thresholds the
// accuracy tests assert and front_end.json's `holds` reports).
inline constexpr double kMinBoundaryIou = 0.97;
inline constexpr double kCornerTolerance = 0.01;  // of the projected page diagonal
inline constexpr double kLineTolerancePx = 2.0;   // a segment point this close is on a line
inline constexpr double kMinLinePrecision = 0.95;
inline constexpr double kMinLineRecall = 0.5;

// Segments of polylines bucketed on a grid of `cell` pixels, for distance
// queries near them.
class SegmentIndex {
 public:
  explicit SegmentIndex(double cell) : cell_(cell) {}
  void Add(const Eigen::Vector2d& a, const Eigen::Vector2d& b);
  void AddPolyline(const std::vector<Eigen::Vector2d>& points);
  // Distance to the nearest segment; +inf beyond about one cell.
  double Distance(const Eigen::Vector2d& p) const;

 private:
  int Cell(double v) const { return int(std::floor(v / cell_)); }
  double cell_;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segments_;
  std::map<std::pair<int, int>, std::vector<int>> grid_;
};

// The truth as one image shows it, in that image's pixels.
struct TruthInView {
  int width = 0, height = 0;
  cv::Mat1b page;                          // 255 where the page is seen
  std::array<Eigen::Vector2d, 4> corners;  // TL TR BR BL of flat.png
  std::array<CornerView, 4> corner_views;
  double diagonal = 0;  // pixels
  std::vector<std::vector<Eigen::Vector2d>> outline;
  std::vector<TrueLine> lines;  // TruthLines(gt), visible pieces
  bool page_cut = false;        // some true corner lies outside the image
};
TruthInView SeeTruth(const GroundTruth& gt, const PinholeCamera& camera);

// The lens sfm took out of reference.png: it undistorts the photo keeping K
// (common/camera.h), so the truth seen by the photo's true camera moves by
// the same map.
struct Undistortion {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  std::array<double, 4> coefficients{};  // OpenCV k1 k2 p1 p2
  bool Any() const;
};
TruthInView Undistort(const TruthInView& truth, const Undistortion& lens);

struct BoundaryFigures {
  double iou = 0;                 // detected mask against the true page region
  double diagonal_px = 0;         // projected page diagonal
  double worst_corner_px = 0;     // over true corners seen: distance to the nearest detected corner
  int corners_seen = 0;           // true corners inside the image and not hidden
  bool corner_hidden = false;     // a true corner in the image is hidden by the page
  bool corners_in_order = false;  // the detected corner nearest the true TL is corners[0]
  double real_off_edge_px = 0;    // 95th percentile distance of real side points from the true edge
  double real_off_edge_max_px = 0;
  double edge_recall = 0;  // visible true outline covered by real sides (within
                           // 1 % of the diagonal)
  bool page_cut = false;   // truth: the image border cuts the page
  int sides_not_real = 0;  // detected sides flagged not real

  double WorstCornerFraction() const { return diagonal_px > 0 ? worst_corner_px / diagonal_px : 0; }
  bool IouHolds() const { return iou >= kMinBoundaryIou; }
  // Corners, and real sides that lie on the true edge and cover it. Not
  // judged when a true corner is hidden: the outline's turns are then fold
  // silhouettes, not corners.
  bool CornersHold() const;
  bool SidesHold() const;
  // A cut page has a side flagged not real; a whole page has none.
  bool CutFlagsHold() const { return page_cut ? sides_not_real >= 1 : sides_not_real == 0; }
  bool AllHold() const { return IouHolds() && CornersHold() && SidesHold() && CutFlagsHold(); }
};
BoundaryFigures MeasureBoundary(const TruthInView& truth, const cv::Mat1b& mask,
                                const Boundary& boundary);

struct LineFigures {
  double precision = 1, precision_text = 1,
         precision_edge = 1;                            // share of detected length
  double recall = 0, recall_text = 0, recall_rule = 0;  // share of true length
  double detected_length = 0, true_length = 0;          // pixels
  int text_segments = 0, edge_segments = 0;
};
// Precision: share of the segments' length within kLineTolerancePx of a true
// line of a matching kind (text on baselines; edges on rules and page
// edges). Recall: share of the true text and rule lines' length, inside the
// page region less detect-features' default margin (0.6 % of the image
// diagonal), that a segment of the matching kind passes within the tolerance.
LineFigures MeasureLines(const TruthInView& truth, const std::vector<FeatureSegment>& segments);

Json ToJson(const BoundaryFigures& f);
Json ToJson(const LineFigures& f);

struct FrontEndInputs {
  fs::path data;  // data set with ground_truth/ (true surface and cameras)
  fs::path work;  // 10_sfm/cameras.json, 20_boundary/, 30_features/
};
struct FrontEndResult {
  std::string reference;
  bool has_boundary = false;  // 20_boundary/ was there
  BoundaryFigures boundary;
  bool has_lines = false;  // 30_features/features.json was there
  LineFigures lines;
  bool recall_required = false;  // LineRecallRequired: a text page or a table
  Json document;                 // docunfold.front-end-metrics
};
// Measures whatever of 20_boundary/ and 30_features/ the work directory
// holds; the document's producer records `options_record`. Throws
// InputError for a missing or malformed input (naming it).
FrontEndResult RunFrontEnd(const FrontEndInputs& inputs, const Json& options_record);

// One line for the log: the reference view and the figures measured.
std::string Summary(const FrontEndResult& result);

}  // namespace docunfold::evaluate
