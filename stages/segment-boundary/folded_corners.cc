// A page corner folded over or under the page (a dog-ear) leaves the outline
// a fifth side, the fold, and corner finding puts the page's corner at one
// of its ends. The page's corner is where the two sides' lines meet past the
// fold; this step puts it there and runs both sides on to it.
#include <algorithm>
#include <cmath>
#include <functional>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "stages/segment-boundary/boundary_internal.h"

namespace docunfold::boundary::internal {
namespace {

using Polyline = std::vector<cv::Point2d>;

// Straight within 3 px plus 1 % of the chord: a page edge in a photo bows a
// little with the lens and the paper, and print next to a fold notches it;
// a fold's kink turns by 20 degrees and more.
double StraightTolerance(double chord) { return 3.0 + 0.01 * chord; }

double DistanceToChord(const cv::Point2d& p, const cv::Point2d& a, const cv::Point2d& b) {
  const cv::Point2d d = b - a;
  const double n = cv::norm(d);
  if (n < 1e-9) return cv::norm(p - a);
  return std::abs(d.x * (p.y - a.y) - d.y * (p.x - a.x)) / n;
}

// The last index m such that q[from..m] is straight (every point within the
// tolerance of the chord q[from] -> q[m]).
size_t StraightRunEnd(const Polyline& q, size_t from) {
  size_t best = from;
  for (size_t m = from + 1; m < q.size(); ++m) {
    const double tol = StraightTolerance(cv::norm(q[m] - q[from]));
    bool straight = true;
    for (size_t j = from + 1; j < m && straight; ++j)
      straight = DistanceToChord(q[j], q[from], q[m]) <= tol;
    if (straight) best = m;
  }
  return best;
}

struct Line {
  cv::Point2d point, direction;  // direction of unit length
};

Line FitLine(const Polyline& q, size_t from, size_t to) {
  std::vector<cv::Point2f> pts;
  for (size_t i = from; i <= to; ++i) pts.emplace_back(q[i]);
  cv::Vec4f l;
  cv::fitLine(pts, l, cv::DIST_L2, 0, 0.01, 0.01);
  cv::Point2d d(l[0], l[1]);
  if (d.dot(q[to] - q[from]) < 0) d = -d;  // along the run
  return {cv::Point2d(l[2], l[3]), d};
}

double AngleDeg(const cv::Point2d& u, const cv::Point2d& v) {
  const double c = u.dot(v) / std::max(1e-12, cv::norm(u) * cv::norm(v));
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180 / CV_PI;
}

// Side s as stored starts at corner kSideStart[s] (top and bottom run left to
// right, left and right top to bottom).
constexpr int kSideStart[4] = {0, 1, 3, 0};

// Side s from `corner` on, resampled every 2 px or closer (the stored side
// is simplified: a straight stretch is two points).
Polyline FromCorner(const Side& side, int s, int corner) {
  Polyline p = side.points;
  if (kSideStart[s] != corner) std::reverse(p.begin(), p.end());
  Polyline dense;
  for (size_t i = 0; i + 1 < p.size(); ++i) {
    const int steps = std::max(1, int(std::ceil(cv::norm(p[i + 1] - p[i]) / 2.0)));
    for (int k = 0; k < steps; ++k) dense.push_back(p[i] + (p[i + 1] - p[i]) * (double(k) / steps));
  }
  if (!p.empty()) dense.push_back(p.back());
  return dense;
}

Polyline ToStored(Polyline p, int s, int corner) {
  if (kSideStart[s] != corner) std::reverse(p.begin(), p.end());
  return p;
}

struct Completion {
  cv::Point2d corner, fold_end;
  Polyline kinked_visible, straight_visible;  // from the fold onwards
};

// The page's corner past a fold that starts at the corner found, with
// `kinked` the side that runs along the fold first and `straight` the other
// (both from the corner found); nullopt when the outline there is no folded
// corner.
std::optional<Completion> TryCorner(const Polyline& kinked, const Polyline& straight,
                                    const cv::Mat1b& mask, const BorderTest& on_border,
                                    const std::function<bool(const cv::Point2d&)>& crease_end,
                                    double perimeter) {
  if (kinked.size() < 4 || straight.size() < 3) return std::nullopt;
  const double min_run = 0.04 * perimeter;
  // The fold: a straight run from the corner found to a kink.
  const size_t k = StraightRunEnd(kinked, 0);
  if (k == 0 || k + 2 >= kinked.size()) return std::nullopt;
  const cv::Point2d c = kinked[0], fold_end = kinked[k];
  // Shorter folds were a panel's bent edge as often as a dog-ear.
  if (cv::norm(fold_end - c) < 0.065 * perimeter) return std::nullopt;
  if (on_border(cv::Point(cvRound(0.5 * (c.x + fold_end.x)), cvRound(0.5 * (c.y + fold_end.y)))))
    return std::nullopt;  // along the image border: a cut, not a fold
  // The side past the kink, from beyond the kink's rounding.
  size_t from = k;
  while (from + 1 < kinked.size() && cv::norm(kinked[from] - fold_end) < 0.02 * perimeter) ++from;
  const size_t to = StraightRunEnd(kinked, from);
  if (to <= from || cv::norm(kinked[to] - kinked[from]) < min_run) return std::nullopt;
  const Line far = FitLine(kinked, from, to);
  // The other side, straight from the corner found.
  const size_t j = StraightRunEnd(straight, 0);
  if (j == 0 || cv::norm(straight[j] - straight[0]) < min_run) return std::nullopt;
  const Line along = FitLine(straight, 0, j);

  // A folded corner turns by less than a page corner at each end of its
  // fold; together they turn as much as the page's corner would.
  const double at_c = AngleDeg(along.direction, fold_end - c);
  const double at_k = AngleDeg(c - fold_end, far.direction);
  if (at_c < 110 || at_c > 160 || at_k < 110 || at_k > 160) return std::nullopt;
  const auto s = LineMeeting(along.point, along.direction, far.point, far.direction, 1e-6);
  if (!s) return std::nullopt;
  const cv::Point2d v = along.point + *s * along.direction;
  // The page's corner lies behind both sides' visible parts.
  if ((c - v).dot(along.direction) <= 0 || (fold_end - v).dot(far.direction) <= 0)
    return std::nullopt;
  const double at_v = AngleDeg(along.direction, far.direction);
  if (at_v < 50 || at_v > 130) return std::nullopt;
  if (cv::norm(v - c) < 0.02 * perimeter || cv::norm(v - fold_end) < 0.02 * perimeter)
    return std::nullopt;
  if (v.x < 0 || v.y < 0 || v.x > mask.cols - 1 || v.y > mask.rows - 1 ||
      on_border(cv::Point(cvRound(v.x), cvRound(v.y))))
    return std::nullopt;  // past the image: the border case
  // What the fold took away is not page in the photo.
  const std::vector<cv::Point> triangle = {cv::Point(cvRound(v.x), cvRound(v.y)),
                                           cv::Point(cvRound(c.x), cvRound(c.y)),
                                           cv::Point(cvRound(fold_end.x), cvRound(fold_end.y))};
  const cv::Rect box = cv::boundingRect(triangle) & cv::Rect(0, 0, mask.cols, mask.rows);
  if (box.area() == 0) return std::nullopt;
  cv::Mat1b inside(box.size(), uchar(0));
  std::vector<cv::Point> local;
  for (const auto& p : triangle) local.push_back(p - box.tl());
  cv::fillConvexPoly(inside, local, cv::Scalar(255));
  const int total = cv::countNonZero(inside);
  cv::Mat1b page;
  cv::bitwise_and(inside, mask(box), page);
  if (total == 0 || cv::countNonZero(page) > 0.2 * total) return std::nullopt;
  if (total > 0.25 * cv::countNonZero(mask)) return std::nullopt;

  // A crease that meets the side kinks the outline the same way; its
  // shading step runs on across the page, a fold's does not.
  if (crease_end(c) || crease_end(fold_end)) return std::nullopt;
  Completion out;
  out.corner = v;
  out.fold_end = fold_end;
  out.kinked_visible.assign(kinked.begin() + long(k), kinked.end());
  out.straight_visible = straight;
  return out;
}

}  // namespace

std::vector<FoldedCorner> CompleteFoldedCorners(const std::vector<cv::Point>& contour,
                                                const ShadingImage& shading,
                                                const BorderTest& on_border, double epsilon_px,
                                                BoundaryResult* r) {
  const cv::Mat1b& mask = r->mask;
  // Whether a shading step runs from `p` across the page to some point of
  // the outline at least a tenth of it away.
  const int n = int(contour.size());
  const auto crease_end = [&](const cv::Point2d& p) {
    int nearest = 0;
    for (int i = 1; i < n; ++i)
      if (cv::norm(cv::Point2d(contour[i]) - p) < cv::norm(cv::Point2d(contour[nearest]) - p))
        nearest = i;
    const int step = std::max(1, n / 100);
    for (int s = n / 10; s <= n - n / 10; s += step)
      if (detail::IsShadingStep(shading.grey, shading.mask, shading.scale, contour[nearest],
                                contour[(nearest + s) % n]))
        return true;
    return false;
  };
  std::vector<FoldedCorner> folded;
  double perimeter = 0;
  for (const Side& side : r->sides) perimeter += PolylineLength(side.points);
  for (int corner = 0; corner < 4; ++corner) {
    const int after = corner, before = (corner + 3) % 4;  // the sides meeting there
    if (!r->corner_in_image[corner] || !r->sides[after].real || !r->sides[before].real) continue;
    for (const auto& [kinked_side, straight_side] : {std::pair{after, before}, {before, after}}) {
      const auto done = TryCorner(FromCorner(r->sides[kinked_side], kinked_side, corner),
                                  FromCorner(r->sides[straight_side], straight_side, corner), mask,
                                  on_border, crease_end, perimeter);
      if (!done) continue;
      folded.push_back({corner, r->corners[corner], done->fold_end});
      r->corners[corner] = done->corner;
      for (const auto& [s, visible] : {std::pair{kinked_side, &done->kinked_visible},
                                       {straight_side, &done->straight_visible}}) {
        Polyline whole = {done->corner};
        whole.insert(whole.end(), visible->begin(), visible->end());
        // The side is page edge all along, though part of it is folded
        // away: straightened, it runs on to the corner.
        Side& side = r->sides[s];
        Polyline simple = Simplify(whole, epsilon_px, false);  // in float: ends exact again
        simple.front() = whole.front();
        simple.back() = whole.back();
        side.points = ToStored(simple, s, corner);
        side.real_parts = {side.points};
      }
      break;
    }
  }
  return folded;
}

}  // namespace docunfold::boundary::internal
