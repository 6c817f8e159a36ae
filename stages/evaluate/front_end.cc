#include "stages/evaluate/front_end.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/errors.h"
#include "common/program.h"

namespace docunfold::evaluate {
namespace {

using Polyline = std::vector<Eigen::Vector2d>;

double DistanceToPolylines(const Eigen::Vector2d& p, const std::vector<Polyline>& lines) {
  double best = std::numeric_limits<double>::infinity();
  for (const Polyline& l : lines)
    for (size_t i = 0; i + 1 < l.size(); ++i) {
      const Eigen::Vector2d a = l[i], d = l[i + 1] - l[i];
      const double t =
          d.squaredNorm() > 0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      best = std::min(best, (a + t * d - p).norm());
    }
  return best;
}

// Calls `visit(point, length)` about every `step_px` along a polyline, each
// piece of it standing for `length`; with step_px = kEverySegment, once per
// segment at its midpoint.
constexpr double kEverySegment = std::numeric_limits<double>::infinity();
template <typename Visit>
void WalkPolyline(const Polyline& line, double step_px, Visit visit) {
  for (size_t k = 0; k + 1 < line.size(); ++k) {
    const Eigen::Vector2d a = line[k], d = line[k + 1] - line[k];
    const int steps = std::max(1, int(std::ceil(d.norm() / step_px)));
    for (int j = 0; j < steps; ++j) visit(a + d * ((j + 0.5) / steps), d.norm() / steps);
  }
}

// part / whole, or `if_empty` when there is nothing to share.
double Share(double part, double whole, double if_empty) {
  return whole > 0 ? part / whole : if_empty;
}

}  // namespace

void SegmentIndex::AddPolyline(const std::vector<Eigen::Vector2d>& points) {
  for (size_t k = 0; k + 1 < points.size(); ++k) Add(points[k], points[k + 1]);
}

void SegmentIndex::Add(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const int id = int(segments_.size());
  segments_.push_back({a, b});
  const int x0 = Cell(std::min(a.x(), b.x())), x1 = Cell(std::max(a.x(), b.x()));
  const int y0 = Cell(std::min(a.y(), b.y())), y1 = Cell(std::max(a.y(), b.y()));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) grid_[{x, y}].push_back(id);
}

double SegmentIndex::Distance(const Eigen::Vector2d& p) const {
  double best = std::numeric_limits<double>::infinity();
  const int cx = Cell(p.x()), cy = Cell(p.y());
  for (int y = cy - 1; y <= cy + 1; ++y)
    for (int x = cx - 1; x <= cx + 1; ++x) {
      auto it = grid_.find({x, y});
      if (it == grid_.end()) continue;
      for (int id : it->second) {
        const auto& [a, b] = segments_[size_t(id)];
        const Eigen::Vector2d d = b - a;
        const double t =
            d.squaredNorm() > 0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
        best = std::min(best, (a + t * d - p).norm());
      }
    }
  return best;
}

TruthInView SeeTruth(const GroundTruth& gt, const PinholeCamera& camera) {
  TruthInView t;
  t.width = camera.width;
  t.height = camera.height;
  t.page = TruePageMask(gt, camera);
  t.corners = TrueCorners(gt, camera);
  t.corner_views = TrueCornersInView(gt, camera);
  t.diagonal = ProjectedDiagonal(gt, camera);
  t.outline = TrueOutlineInView(gt, camera, 2.0);
  GroundTruth with_lines = gt;
  with_lines.lines = TruthLines(gt);
  t.lines = TrueLinesInView(with_lines, camera, 2.0);
  for (const Eigen::Vector2d& c : t.corners)
    t.page_cut = t.page_cut || c.x() < 0 || c.y() < 0 || c.x() > camera.width - 1 ||
                 c.y() > camera.height - 1;
  return t;
}

bool Undistortion::Any() const {
  return std::any_of(coefficients.begin(), coefficients.end(), [](double c) { return c != 0; });
}

TruthInView Undistort(const TruthInView& truth, const Undistortion& lens) {
  if (!lens.Any()) return truth;
  cv::Mat K;
  cv::eigen2cv(lens.K, K);
  const cv::Mat dist = (cv::Mat_<double>(1, 4) << lens.coefficients[0], lens.coefficients[1],
                        lens.coefficients[2], lens.coefficients[3]);
  auto move = [&](const Polyline& in) { return UndistortPixels(lens.K, lens.coefficients, in); };
  TruthInView t = truth;
  // The same map sfm's UndistortPhoto applies to the photo.
  cv::Mat map1, map2;
  cv::initUndistortRectifyMap(K, dist, cv::Mat(), K, truth.page.size(), CV_32FC1, map1, map2);
  cv::remap(truth.page, t.page, map1, map2, cv::INTER_NEAREST, cv::BORDER_CONSTANT);
  const Polyline corners = move(Polyline(truth.corners.begin(), truth.corners.end()));
  std::copy(corners.begin(), corners.end(), t.corners.begin());
  t.diagonal = 0.5 * ((t.corners[2] - t.corners[0]).norm() + (t.corners[3] - t.corners[1]).norm());
  for (Polyline& piece : t.outline) piece = move(piece);
  for (TrueLine& line : t.lines) line.points = move(line.points);
  return t;
}

bool BoundaryFigures::CornersHold() const {
  return corner_hidden || worst_corner_px <= kCornerTolerance * diagonal_px;
}

bool BoundaryFigures::SidesHold() const {
  // Locally (a speck, a rendered page edge thicker than the true mesh's) a
  // side may stray up to three times the tolerance.
  const double tol = kCornerTolerance * diagonal_px;
  return corner_hidden ||
         (real_off_edge_px <= tol && real_off_edge_max_px <= 3 * tol && edge_recall >= 0.9);
}

BoundaryFigures MeasureBoundary(const TruthInView& truth, const cv::Mat1b& mask,
                                const Boundary& boundary) {
  BoundaryFigures f;
  if (mask.size() != truth.page.size())
    throw InputError("boundary mask is " + std::to_string(mask.cols) + "x" +
                     std::to_string(mask.rows) + ", the reference view " +
                     std::to_string(truth.width) + "x" + std::to_string(truth.height));
  const cv::Mat1b detected = mask > 0;
  const double inter = cv::countNonZero(detected & truth.page);
  const double uni = cv::countNonZero(detected | truth.page);
  f.iou = Share(inter, uni, 0);
  f.diagonal_px = truth.diagonal;
  f.page_cut = truth.page_cut;
  int nearest_to_tl = -1;
  for (int i = 0; i < 4; ++i) {
    double best = std::numeric_limits<double>::infinity();
    int best_j = -1;
    for (int j = 0; j < 4; ++j) {
      const double d = (boundary.corners[size_t(j)] - truth.corners[size_t(i)]).norm();
      if (d < best) {
        best = d;
        best_j = j;
      }
    }
    if (i == 0) nearest_to_tl = best_j;
    f.corner_hidden = f.corner_hidden || truth.corner_views[size_t(i)] == CornerView::kHidden;
    if (truth.corner_views[size_t(i)] == CornerView::kVisible) {
      f.worst_corner_px = std::max(f.worst_corner_px, best);
      ++f.corners_seen;
    }
  }
  f.corners_in_order = nearest_to_tl == 0;
  // Real sides lie on the true outline, and cover it.
  std::vector<Polyline> real;
  for (const BoundarySide& side : boundary.sides) {
    f.sides_not_real += !side.real;
    for (const Polyline& part : side.real_parts) real.push_back(part);
  }
  std::vector<double> off;
  for (const Polyline& part : real)
    WalkPolyline(part, 2.0, [&](const Eigen::Vector2d& p, double) {
      off.push_back(DistanceToPolylines(p, truth.outline));
    });
  if (!off.empty()) {
    std::sort(off.begin(), off.end());
    f.real_off_edge_px = off[size_t(0.95 * double(off.size() - 1))];
    f.real_off_edge_max_px = off.back();
  }
  double covered = 0, total = 0;
  for (const Polyline& piece : truth.outline)
    WalkPolyline(piece, kEverySegment, [&](const Eigen::Vector2d& m, double length) {
      total += length;
      if (DistanceToPolylines(m, real) <= kCornerTolerance * f.diagonal_px) covered += length;
    });
  f.edge_recall = Share(covered, total, 0);
  return f;
}

LineFigures MeasureLines(const TruthInView& truth, const std::vector<FeatureSegment>& segments) {
  SegmentIndex true_text(8), true_edge(8), found_text(8), found_edge(8);
  for (const TrueLine& l : truth.lines)
    (l.kind == "text" ? true_text : true_edge).AddPolyline(l.points);
  LineFigures f;
  double good_text = 0, all_text = 0, good_edge = 0, all_edge = 0;
  for (const FeatureSegment& s : segments) {
    const bool text = s.kind == "text";
    (text ? f.text_segments : f.edge_segments)++;
    (text ? found_text : found_edge).AddPolyline(s.points);
    WalkPolyline(s.points, 1.0, [&](const Eigen::Vector2d& p, double length) {
      const bool good = (text ? true_text : true_edge).Distance(p) <= kLineTolerancePx;
      (text ? all_text : all_edge) += length;
      (text ? good_text : good_edge) += good ? length : 0.0;
    });
  }
  f.detected_length = all_text + all_edge;
  f.precision_text = Share(good_text, all_text, 1);
  f.precision_edge = Share(good_edge, all_edge, 1);
  f.precision = Share(good_text + good_edge, f.detected_length, 1);
  // Recall inside the region detect-features searches by default: the page
  // less a margin of 0.6 % of the image diagonal (at least 4 px).
  const int margin = std::max(4, int(std::lround(0.006 * std::hypot(truth.width, truth.height))));
  cv::Mat1b region;
  cv::erode(truth.page, region,
            cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin + 1, 2 * margin + 1)));
  double covered_text = 0, length_text = 0, covered_rule = 0, length_rule = 0;
  for (const TrueLine& l : truth.lines) {
    if (l.kind == "border") continue;
    const bool text = l.kind == "text";
    WalkPolyline(l.points, kEverySegment, [&](const Eigen::Vector2d& m, double length) {
      const int x = int(std::lround(m.x())), y = int(std::lround(m.y()));
      if (x < 0 || y < 0 || x >= region.cols || y >= region.rows || !region(y, x)) return;
      const bool covered = (text ? found_text : found_edge).Distance(m) <= kLineTolerancePx;
      (text ? length_text : length_rule) += length;
      (text ? covered_text : covered_rule) += covered ? length : 0.0;
    });
  }
  f.true_length = length_text + length_rule;
  f.recall_text = Share(covered_text, length_text, 0);
  f.recall_rule = Share(covered_rule, length_rule, 0);
  f.recall = Share(covered_text + covered_rule, f.true_length, 0);
  return f;
}

Json ToJson(const BoundaryFigures& f) {
  return {{"iou", NumberOrNull(f.iou)},
          {"diagonal_px", NumberOrNull(f.diagonal_px)},
          {"worst_corner_px", NumberOrNull(f.worst_corner_px)},
          {"worst_corner_fraction", NumberOrNull(f.WorstCornerFraction())},
          {"corners_seen", f.corners_seen},
          {"corner_hidden", f.corner_hidden},
          {"corners_in_order", f.corners_in_order},
          {"real_off_edge_px", NumberOrNull(f.real_off_edge_px)},
          {"real_off_edge_max_px", NumberOrNull(f.real_off_edge_max_px)},
          {"edge_recall", NumberOrNull(f.edge_recall)},
          {"page_cut", f.page_cut},
          {"sides_not_real", f.sides_not_real},
          {"holds",
           {{"iou", f.IouHolds()},
            {"corners", f.CornersHold()},
            {"sides", f.SidesHold()},
            {"cut_flags", f.CutFlagsHold()}}}};
}

Json ToJson(const LineFigures& f) {
  return {{"precision", NumberOrNull(f.precision)},
          {"precision_text", NumberOrNull(f.precision_text)},
          {"precision_edge", NumberOrNull(f.precision_edge)},
          {"recall", NumberOrNull(f.recall)},
          {"recall_text", NumberOrNull(f.recall_text)},
          {"recall_rule", NumberOrNull(f.recall_rule)},
          {"detected_length_px", NumberOrNull(f.detected_length)},
          {"true_length_px", NumberOrNull(f.true_length)},
          {"text_segments", f.text_segments},
          {"edge_segments", f.edge_segments}};
}

FrontEndResult RunFrontEnd(const FrontEndInputs& in, const Json& options_record) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path cameras_file = in.work / "10_sfm" / "cameras.json";
  const Json cameras_doc = ReadJsonFile(cameras_file);
  const CameraSet cameras = ReadCameras(cameras_file);
  const PinholeCamera* ours = cameras.Find(cameras.reference);
  if (!ours)
    throw InputError(cameras_file.string() + ": the reference view " + cameras.reference +
                     " is not among the views");
  const GroundTruth gt = LoadGroundTruth(in.data);
  const PinholeCamera* photo = gt.cameras.Find(cameras.reference);
  if (!photo)
    throw InputError((in.data / "ground_truth" / "cameras.json").string() + ": no view " +
                     cameras.reference + " (sfm's reference)");
  if (photo->width != ours->width || photo->height != ours->height)
    throw InputError(cameras_file.string() + ": reference " + cameras.reference + " is " +
                     std::to_string(ours->width) + "x" + std::to_string(ours->height) +
                     ", its true camera " + std::to_string(photo->width) + "x" +
                     std::to_string(photo->height));
  // reference.png is the photo undistorted by sfm's lens with sfm's K kept;
  // the truth seen by the photo's true camera moves the same way, so the
  // figures judge the stages and not sfm's calibration.
  Undistortion lens;
  lens.K = ours->K;
  if (cameras_doc.value("reference_undistorted", false)) {
    JsonReader r(cameras_doc, cameras_file);
    for (size_t v = 0; v < cameras.views.size(); ++v)
      if (cameras_doc["views"][v].contains("distortion")) {
        lens.coefficients = ReadDistortion(r, "/views/" + std::to_string(v));
        break;
      }
  }
  const TruthInView truth = Undistort(SeeTruth(gt, *photo), lens);

  FrontEndResult result;
  result.reference = cameras.reference;
  result.recall_required = LineRecallRequired(gt);
  Json doc = MakeHeader("docunfold.front-end-metrics", 1, "evaluate", options_record);
  doc["data"] = fs::absolute(in.data).lexically_normal().string();
  doc["reference"] = cameras.reference;
  doc["reference_undistorted"] = lens.Any();
  doc["thresholds"] = {{"boundary_iou", kMinBoundaryIou},
                       {"corner_fraction_of_diagonal", kCornerTolerance},
                       {"line_tolerance_px", kLineTolerancePx},
                       {"line_precision", kMinLinePrecision},
                       {"line_recall", kMinLineRecall}};
  const fs::path boundary_file = in.work / "20_boundary" / "boundary.json";
  const fs::path mask_file = in.work / "20_boundary" / "mask.png";
  if (fs::exists(boundary_file) || fs::exists(mask_file)) {
    const Boundary boundary = ReadBoundary(boundary_file);
    const cv::Mat1b mask = ReadDocumentMask(mask_file, truth.width, truth.height);
    result.has_boundary = true;
    result.boundary = MeasureBoundary(truth, mask, boundary);
    doc["boundary"] = ToJson(result.boundary);
  } else {
    doc["boundary"] = Json{{"skipped", "no 20_boundary/boundary.json"}};
  }
  const fs::path features_file = in.work / "30_features" / "features.json";
  if (fs::exists(features_file)) {
    const FeatureFile features = ReadFeatures(features_file);
    result.has_lines = true;
    result.lines = MeasureLines(truth, features.segments);
    doc["features"] = ToJson(result.lines);
    doc["features"]["producer"] = features.producer;
    doc["features"]["recall_required"] = result.recall_required;
    doc["features"]["holds"] = {
        {"precision", result.lines.precision >= kMinLinePrecision},
        {"recall", !result.recall_required || result.lines.recall >= kMinLineRecall}};
  } else {
    doc["features"] = Json{{"skipped", "no 30_features/features.json"}};
  }
  doc["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.document = std::move(doc);
  return result;
}

std::string Summary(const FrontEndResult& r) {
  std::string summary = "front end in " + r.reference + ":";
  if (r.has_boundary)
    summary += " boundary IoU " + Fixed(r.boundary.iou, 4) + ", worst corner " +
               Fixed(100 * r.boundary.WorstCornerFraction(), 2) + " % of the diagonal, " +
               std::to_string(r.boundary.sides_not_real) + " side(s) not real;";
  if (r.has_lines)
    summary += " features precision " + Fixed(r.lines.precision, 3) + ", recall " +
               Fixed(r.lines.recall, 3);
  return summary;
}

}  // namespace docunfold::evaluate
