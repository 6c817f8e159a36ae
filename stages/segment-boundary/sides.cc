// Steps of segment-boundary along the page's outline: the outline itself,
// and the four sides between its corners with the parts of them that are
// page edge.
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/errors.h"
#include "stages/segment-boundary/boundary_internal.h"

namespace docunfold::boundary::internal {
namespace {

// Drops the points next to either end of a side that lie behind its corner:
// a sharpened corner of a shallow turn (150 degrees and more) moves along
// the outline's rounding, and the points of the rounding past it would make
// the side hook back (init-mesh's Coons patch then folds over there).
std::vector<cv::Point2d> TrimBehindCorners(std::vector<cv::Point2d> p) {
  constexpr double kAhead = 20;  // px: the side's direction at a corner
  for (int end = 0; end < 2 && p.size() > 2; ++end) {
    const cv::Point2d corner = p.front();
    size_t far = 1;
    while (far + 1 < p.size() && cv::norm(p[far] - corner) < kAhead) ++far;
    const cv::Point2d direction = p[far] - corner;
    size_t keep = 1;
    while (keep < far && (p[keep] - corner).dot(direction) <= 0) ++keep;
    p.erase(p.begin() + 1, p.begin() + long(keep));
    std::reverse(p.begin(), p.end());
  }
  return p;
}

}  // namespace

BorderTest OnImageBorder(cv::Size size, double tol) {
  return [size, tol](const cv::Point& p) {
    return p.x <= tol || p.y <= tol || p.x >= size.width - 1 - tol || p.y >= size.height - 1 - tol;
  };
}

std::vector<cv::Point> ClockwiseOutline(const cv::Mat1b& mask) {
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  if (contours.empty()) throw InputError("no document found after refinement");
  std::vector<cv::Point> contour = *std::max_element(
      contours.begin(), contours.end(),
      [](const auto& a, const auto& b) { return cv::contourArea(a) < cv::contourArea(b); });
  if (SignedArea(contour) < 0) std::reverse(contour.begin(), contour.end());
  return contour;
}

double PolylineLength(const std::vector<cv::Point2d>& p) {
  double l = 0;
  for (size_t i = 1; i < p.size(); ++i) l += cv::norm(p[i] - p[i - 1]);
  return l;
}

std::optional<double> LineMeeting(const cv::Point2d& a, const cv::Point2d& da, const cv::Point2d& b,
                                  const cv::Point2d& db, double min_sine) {
  const double cross = da.x * db.y - da.y * db.x;
  if (std::abs(cross) < min_sine) return std::nullopt;
  const cv::Point2d w = b - a;
  return (w.x * db.y - w.y * db.x) / cross;
}

std::vector<cv::Point2d> ToDouble(const std::vector<cv::Point>& pts) {
  return std::vector<cv::Point2d>(pts.begin(), pts.end());
}

std::vector<cv::Point2d> Simplify(const std::vector<cv::Point2d>& pts, double eps, bool closed) {
  if (pts.size() < 3) return pts;
  std::vector<cv::Point2f> in(pts.begin(), pts.end()), out;
  cv::approxPolyDP(in, out, eps, closed);
  return std::vector<cv::Point2d>(out.begin(), out.end());
}

Side TraceSide(const std::vector<cv::Point>& contour, const std::array<int, 4>& idx, int i,
               const std::array<cv::Point2d, 4>& corners, const BorderTest& on_border,
               const BoundaryOptions& options) {
  const int n = int(contour.size());
  const int from = idx[i], to = idx[(i + 1) % 4];
  std::vector<cv::Point> path;
  for (int k = from;; k = (k + 1) % n) {
    path.push_back(contour[k]);
    if (k == to) break;
  }
  // Along the clockwise outline: top TL->TR, right TR->BR, then BR->BL and
  // BL->TL, which the schema stores reversed (bottom BL->BR, left TL->BL).
  const bool reversed = (i == kBottom || i == kLeft);
  if (reversed) std::reverse(path.begin(), path.end());
  Side side;
  double cut = 0, total = 0;
  std::vector<cv::Point2d> run;
  auto flush = [&] {
    if (run.size() >= 2 && PolylineLength(run) >= 4.0)
      side.real_parts.push_back(Simplify(run, options.contour_epsilon_px, false));
    run.clear();
  };
  for (size_t k = 0; k < path.size(); ++k) {
    const bool border = on_border(path[k]);
    if (k > 0) {
      const double l = cv::norm(path[k] - path[k - 1]);
      total += l;
      if (border && on_border(path[k - 1])) cut += l;
    }
    if (border)
      flush();
    else
      run.push_back(path[k]);
  }
  flush();
  side.cut_fraction = total > 0 ? cut / total : 0;
  side.real = side.cut_fraction <= options.max_cut_fraction;
  side.points = Simplify(ToDouble(path), options.contour_epsilon_px, false);
  if (side.points.size() < 2) side.points = {cv::Point2d(path.front()), cv::Point2d(path.back())};
  // A side runs from corner to corner, sharpened as the corners are.
  side.points.front() = corners[reversed ? (i + 1) % 4 : i];
  side.points.back() = corners[reversed ? i : (i + 1) % 4];
  side.points = TrimBehindCorners(std::move(side.points));
  if (side.real) side.real_parts = {side.points};
  return side;
}

}  // namespace docunfold::boundary::internal
