// Step 3 of segment-boundary: the page's four corners on its outline, and
// the helpers the tests call (detail::).
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/image_sampling.h"
#include "stages/segment-boundary/boundary_internal.h"

namespace docunfold::boundary {
namespace internal {

double SignedArea(const std::vector<cv::Point>& c) {
  double a = 0;
  for (size_t i = 0, n = c.size(); i < n; ++i) {
    const cv::Point& p = c[i];
    const cv::Point& q = c[(i + 1) % n];
    a += double(p.x) * q.y - double(q.x) * p.y;
  }
  return 0.5 * a;
}

// Outline points on either side of a point over which its turning is
// measured, and its corner's sides fitted: a few percent of the outline.
int CornerReach(size_t outline_points) { return std::max(2, int(0.025 * double(outline_points))); }

}  // namespace internal

using internal::CornerReach;
using internal::LineMeeting;
using internal::SignedArea;

namespace {

// Fraction of the outline's area enclosed by the outline from point i to
// point j (clockwise) closed by the chord j-i.
double ChordSideArea(const std::vector<cv::Point>& contour, int i, int j) {
  const int n = int(contour.size());
  std::vector<cv::Point> part;
  for (int k = i;; k = (k + 1) % n) {
    part.push_back(contour[k]);
    if (k == j) break;
  }
  const double total = std::abs(SignedArea(contour));
  return total > 0 ? std::abs(SignedArea(part)) / total : 0;
}

// Whether index k lies strictly between from and to going forward round an
// outline of n points.
bool OnOutlinePath(int n, int from, int to, int k) {
  const int span = ((to - from) % n + n) % n, at = ((k - from) % n + n) % n;
  return at > 0 && at < span;
}

double TriangleArea(const cv::Point& a, const cv::Point& b, const cv::Point& c) {
  return 0.5 * std::abs(double(b.x - a.x) * (c.y - a.y) - double(c.x - a.x) * (b.y - a.y));
}

// Outline steps from corner `i` of `corners` to the next corner
// (`direction` +1) or back to the previous one (-1).
int ArmLength(const std::array<int, 4>& corners, int i, int direction, int n) {
  const int steps =
      direction > 0 ? corners[(i + 1) % 4] - corners[i] : corners[i] - corners[(i + 3) % 4];
  return ((steps % n) + n) % n;
}

// Along the outline from `corner` in `direction`, steps `first` to `last`:
// the point that turns most (by `min_turn` at least) and most of its
// neighbours within `window` steps that lie `compared_from` or more steps
// from the corner; -1 if none. Stops at the image border.
int SharpestTurnOnArm(const std::vector<cv::Point>& contour, const std::vector<double>& angle,
                      int corner, int direction, int first, int last, int window, int compared_from,
                      double min_turn, const std::function<bool(const cv::Point&)>& on_border) {
  const int n = int(contour.size());
  auto wrap = [n](int k) { return ((k % n) + n) % n; };
  int best = -1;
  double best_angle = min_turn;
  for (int s = first; s <= last; ++s) {
    const int k = wrap(corner + direction * s);
    if (on_border(contour[k])) break;
    if (angle[k] < best_angle) continue;
    bool is_max = true;
    for (int j = -window; j <= window && is_max; ++j)
      if (j != 0 && s + j * direction >= compared_from) is_max = angle[wrap(k + j)] <= angle[k];
    if (is_max) {
      best = k;
      best_angle = angle[k];
    }
  }
  return best;
}

}  // namespace

namespace detail {

std::vector<double> TurningAngles(const std::vector<cv::Point>& contour, int reach) {
  const int n = int(contour.size());
  std::vector<double> angle(n, 0.0);
  if (n < 3) return angle;
  reach = std::clamp(reach, 1, std::max(1, n / 3));
  for (int k = 0; k < n; ++k) {
    const cv::Point2d a = contour[(k - reach + n) % n], b = contour[k],
                      c = contour[(k + reach) % n];
    const cv::Point2d u = b - a, v = c - b;
    // Positive where a clockwise (image y down) outline turns right: convex.
    angle[k] = std::atan2(u.x * v.y - u.y * v.x, u.dot(v));
  }
  return angle;
}

std::array<int, 4> FindCornerIndices(const std::vector<cv::Point>& contour,
                                     const FoldTest& is_fold) {
  const int n = int(contour.size());
  if (n < 8) return {{0, n / 4, n / 2, 3 * n / 4}};
  double perimeter = 0;
  for (int k = 0; k < n; ++k) perimeter += cv::norm(contour[(k + 1) % n] - contour[k]);
  // Turning at the scale of a few percent of the outline: page corners turn
  // by 60-120 degrees there, folds and curls by much less, pixel noise not.
  const int reach = CornerReach(contour.size());
  const std::vector<double> angle = TurningAngles(contour, reach);
  // Candidates: convex local maxima of the turning.
  std::vector<int> candidates;
  for (int k = 0; k < n; ++k) {
    if (angle[k] < 15.0 * CV_PI / 180) continue;
    bool is_max = true;
    for (int j = -reach; j <= reach && is_max; ++j)
      if (j != 0) {
        const double other = angle[((k + j) % n + n) % n];
        is_max = other < angle[k] || (other == angle[k] && j > 0);
      }
    if (is_max) candidates.push_back(k);
  }
  std::sort(candidates.begin(), candidates.end(),
            [&](int a, int b) { return angle[a] > angle[b]; });
  if (candidates.size() > 12) candidates.resize(12);
  if (is_fold && candidates.size() > 4) {
    // Both ends of a fold are kinks of the outline, often as sharp as a
    // corner of a foreshortened panel: drop them while four others remain.
    // A chord with only a sliver of page beyond it (under 12 %) may instead
    // join two corners of a side whose flap is shaded differently; it counts
    // as a fold only when the outline round the sliver passes corners that
    // turn more sharply than its ends (a fold close to a side has both page
    // corners beyond it). See docs/decisions/segment-boundary.md, "Corners
    // next to a flap".
    auto sharper_beyond = [&](int a, int b) {
      const double side_area = ChordSideArea(contour, a, b);
      if (std::min(side_area, 1 - side_area) >= 0.12) return true;
      const int shorter_from = side_area <= 0.5 ? a : b;
      const int shorter_to = shorter_from == a ? b : a;
      const double weaker = std::min(angle[a], angle[b]);
      for (const int c : candidates)
        if (c != a && c != b && OnOutlinePath(n, shorter_from, shorter_to, c) && angle[c] >= weaker)
          return true;
      return false;
    };
    std::vector<bool> fold_end(candidates.size(), false);
    for (size_t i = 0; i < candidates.size(); ++i)
      for (size_t j = i + 1; j < candidates.size(); ++j)
        if (is_fold(contour[candidates[i]], contour[candidates[j]]) &&
            sharper_beyond(candidates[i], candidates[j]))
          fold_end[i] = fold_end[j] = true;
    std::vector<int> kept;
    for (size_t i = 0; i < candidates.size(); ++i)
      if (!fold_end[i]) kept.push_back(candidates[i]);
    if (kept.size() >= 4) candidates = kept;
  }
  std::array<int, 4> best{{0, n / 4, n / 2, 3 * n / 4}};
  if (candidates.size() < 4) {
    // Not four distinct turns (a blob, a rounded shape): the quadrilateral
    // of largest area on the convex hull.
    std::vector<int> hull;
    cv::convexHull(contour, hull, false, false);
    std::sort(hull.begin(), hull.end());
    while (hull.size() > 24) {
      size_t worst = 0;
      double worst_area = 1e300;
      const size_t h = hull.size();
      for (size_t i = 0; i < h; ++i) {
        const double a = TriangleArea(contour[hull[(i + h - 1) % h]], contour[hull[i]],
                                      contour[hull[(i + 1) % h]]);
        if (a < worst_area) {
          worst_area = a;
          worst = i;
        }
      }
      hull.erase(hull.begin() + long(worst));
    }
    if (hull.size() < 4) return best;
    candidates = hull;
  }
  // The four candidates that turn most in total while the outline between
  // them stays close to straight: a fold can kink a side as sharply as a
  // corner turns, but then the side through the real corner bends away from
  // its chord far more than the side with the fold does.
  std::sort(candidates.begin(), candidates.end());
  auto chord_deviation = [&](int from, int to) {
    const cv::Point2d a = contour[from], b = contour[to];
    const cv::Point2d d = b - a;
    const double len = cv::norm(d);
    if (len < 1) return 1.0;
    double sum = 0;
    int count = 0;
    for (int k = from; k != to; k = (k + 1) % n, ++count) {
      const cv::Point2d p = cv::Point2d(contour[k]) - a;
      sum += std::abs(d.x * p.y - d.y * p.x) / len;
    }
    return count > 0 ? sum / count / len : 0.0;
  };
  const int m = int(candidates.size());
  double best_score = -1e300;
  for (int a = 0; a < m; ++a)
    for (int b = a + 1; b < m; ++b)
      for (int c = b + 1; c < m; ++c)
        for (int d = c + 1; d < m; ++d) {
          const int q[4] = {candidates[a], candidates[b], candidates[c], candidates[d]};
          double turn = 0, deviation = 0;
          for (int i = 0; i < 4; ++i) {
            turn += angle[q[i]];
            deviation += chord_deviation(q[i], q[(i + 1) % 4]);
          }
          const double score = turn - 10.0 * deviation;
          if (score > best_score) {
            best_score = score;
            best = {{q[0], q[1], q[2], q[3]}};
          }
        }
  return best;
}

std::array<int, 4> MoveBorderCornersToPageCorners(
    const std::vector<cv::Point>& contour, std::array<int, 4> idx,
    const std::function<bool(const cv::Point&)>& on_border, double min_turn_deg,
    double max_arm_fraction) {
  const int n = int(contour.size());
  if (n < 16) return idx;
  const int reach = CornerReach(contour.size());
  const std::vector<double> angle = TurningAngles(contour, reach);
  const std::array<int, 4> found = idx;
  for (int i = 0; i < 4; ++i) {
    const int corner = found[i];
    if (!on_border(contour[corner])) continue;
    const int forward = ArmLength(found, i, +1, n), backward = ArmLength(found, i, -1, n);
    auto arm_on_border = [&](int direction, int length) {
      return on_border(contour[((corner + direction * std::min(reach, length / 2)) % n + n) % n]);
    };
    const bool forward_cut = arm_on_border(+1, forward), backward_cut = arm_on_border(-1, backward);
    // Only an exit: one arm along the border, the other into the image (a
    // real corner that merely touches the border has both arms inside).
    if (forward_cut == backward_cut) continue;
    const int direction = forward_cut ? -1 : +1;
    const int length = forward_cut ? backward : forward;
    // Past the exit's own turning window, and compared only with points past it.
    const int best =
        SharpestTurnOnArm(contour, angle, corner, direction, reach, int(max_arm_fraction * length),
                          reach / 2, reach, min_turn_deg * CV_PI / 180, on_border);
    if (best >= 0) idx[i] = best;
  }
  return idx;
}

std::array<int, 4> MoveFoldEndsToPageCorners(const std::vector<cv::Point>& contour,
                                             std::array<int, 4> idx,
                                             const std::function<bool(const cv::Point&)>& on_border,
                                             const FoldTest& is_fold, double min_turn_deg,
                                             double max_arm_fraction) {
  const int n = int(contour.size());
  if (n < 32 || !is_fold) return idx;
  const int reach = CornerReach(contour.size());
  const int fine = std::max(2, reach / 4);
  const std::vector<double> angle = TurningAngles(contour, fine);
  const double max_fold_turn = 60 * CV_PI / 180;
  const std::array<int, 4> found = idx;
  for (int i = 0; i < 4; ++i) {
    const int corner = found[i];
    if (on_border(contour[corner])) continue;
    // The sharpest fine turn on each arm, past the corner's own turning.
    std::array<int, 2> turn;
    for (int a = 0; a < 2; ++a) {
      const int direction = a == 0 ? +1 : -1;
      turn[a] = SharpestTurnOnArm(contour, angle, corner, direction, 2 * fine,
                                  int(max_arm_fraction * ArmLength(found, i, direction, n)), fine,
                                  0, min_turn_deg * CV_PI / 180, on_border);
    }
    if ((turn[0] >= 0) == (turn[1] >= 0)) continue;  // none, or one on each arm
    // A fold's end turns less than a page corner does, and the corner it
    // hides less than it (else the outline's turning would have found it).
    const int beside = turn[0] >= 0 ? turn[0] : turn[1];
    if (angle[corner] >= max_fold_turn || angle[beside] >= angle[corner]) continue;
    // The crease must start at the corner found, not at the turn beside it
    // (there the corner found may be the page's, the turn the crease's end).
    auto crease_from = [&](int from) {
      for (int s = n / 8; s <= n - n / 8; s += fine)
        if (is_fold(contour[from], contour[(from + s) % n])) return true;
      return false;
    };
    if (crease_from(corner) && !crease_from(beside)) idx[i] = beside;
  }
  return idx;
}

bool IsShadingStep(const cv::Mat1f& grey, const cv::Mat1b& mask, double scale, const cv::Point& a,
                   const cv::Point& b, double offset_px) {
  const cv::Point2d p = cv::Point2d(a) * scale, q = cv::Point2d(b) * scale;
  const double length = cv::norm(q - p);
  if (length < 20) return false;
  const cv::Point2d along = (q - p) / length, normal(-along.y, along.x);
  // Far enough from the line to leave a crease's own shading ramp, near
  // enough to stay on the two panels next to it.
  const double offset = offset_px > 0 ? offset_px : std::max(4.0, 0.02 * length);
  auto inside = [&](const cv::Point2d& x) {
    const int ix = int(std::lround(x.x)), iy = int(std::lround(x.y));
    return ix >= 0 && iy >= 0 && ix < mask.cols && iy < mask.rows && mask(iy, ix) > 0;
  };
  constexpr int kSamples = 15;
  constexpr double kStep = 0.05;  // relative brightness difference across
  int valid = 0, brighter = 0, darker = 0;
  for (int k = 0; k < kSamples; ++k) {
    const cv::Point2d x = p + (q - p) * (0.15 + 0.7 * k / (kSamples - 1));
    // Paper on both sides, well clear of the outline: a page side has the
    // table on one of them.
    if (!inside(x + 2 * offset * normal) || !inside(x - 2 * offset * normal)) continue;
    ++valid;
    const double g1 = SampleBilinear(grey, (x + offset * normal).x, (x + offset * normal).y);
    const double g2 = SampleBilinear(grey, (x - offset * normal).x, (x - offset * normal).y);
    const double step = (g1 - g2) / std::max({g1, g2, 1.0});
    brighter += step > kStep;
    darker += step < -kStep;
  }
  return valid >= 0.8 * kSamples && std::max(brighter, darker) >= 0.7 * valid;
}

cv::Point2d RefineCorner(const std::vector<cv::Point>& contour, int index, int reach) {
  const int n = int(contour.size());
  const cv::Point2d corner = contour[index];
  if (n < 16 || reach < 2) return corner;
  auto at = [&](int offset) { return cv::Point2d(contour[((index + offset) % n + n) % n]); };
  // A straight line through the outline on one side of the corner: the
  // longest window (starting past the rounding) that the line fits within
  // a pixel or two, so that a kink or a notch further along does not tilt it.
  auto fit_side = [&](int direction, cv::Vec4f* line) {
    const int start = std::max(1, reach / 3);
    for (double factor : {4.0, 3.0, 2.0, 1.5, 1.0}) {
      const int end = std::min(n / 3, int(factor * reach));
      if (end - start < 4) continue;
      std::vector<cv::Point2f> pts;
      for (int k = start; k <= end; ++k) pts.emplace_back(at(direction * k));
      cv::fitLine(pts, *line, cv::DIST_HUBER, 0, 0.01, 0.01);
      const cv::Point2d d((*line)[0], (*line)[1]), o((*line)[2], (*line)[3]);
      double sum2 = 0, worst = 0;
      for (const auto& pt : pts) {
        const cv::Point2d r = cv::Point2d(pt) - o;
        const double e = d.x * r.y - d.y * r.x;
        sum2 += e * e;
        worst = std::max(worst, std::abs(e));
      }
      if (std::sqrt(sum2 / pts.size()) <= 1.5 && worst <= 3.0) return true;
    }
    return false;
  };
  cv::Vec4f before, after;
  if (!fit_side(-1, &before) || !fit_side(+1, &after)) return corner;
  const cv::Point2d d1(before[0], before[1]), o1(before[2], before[3]);
  const cv::Point2d d2(after[0], after[1]), o2(after[2], after[3]);
  const auto t = LineMeeting(o1, d1, o2, d2, std::sin(20.0 * CV_PI / 180));
  if (!t) return corner;  // nearly parallel
  const cv::Point2d x = o1 + *t * d1;
  // The rounding the mask leaves is a few pixels: a far intersection means
  // the fits are not of this corner's sides.
  double step = 0;
  for (int k = -reach; k < reach; ++k) step += cv::norm(at(k + 1) - at(k));
  return cv::norm(x - corner) <= 0.5 * step ? x : corner;
}

int GeometricTopSide(const std::array<cv::Point2d, 4>& corners) {
  int top = 0;
  double best = 1e300;
  for (int i = 0; i < 4; ++i) {
    const cv::Point2d d = corners[(i + 1) % 4] - corners[i];
    // Outward normal of a clockwise (image y down) polygon: (d.y, -d.x).
    const double ny = -d.x / std::max(1e-9, cv::norm(d));
    if (ny < best) {
      best = ny;
      top = i;
    }
  }
  return top;
}

}  // namespace detail

namespace internal {

ShadingImage MakeShadingImage(const cv::Mat3b& small, const cv::Mat1b& mask, int full_width) {
  ShadingImage shading;
  cv::Mat1b grey_bytes;
  cv::cvtColor(small, grey_bytes, cv::COLOR_BGR2GRAY);
  grey_bytes.convertTo(shading.grey, CV_32F);
  cv::GaussianBlur(shading.grey, shading.grey, cv::Size(), 3.0);  // text away, shading kept
  cv::resize(mask, shading.mask, small.size(), 0, 0, cv::INTER_AREA);
  shading.mask = shading.mask > 127;
  shading.scale = double(small.cols) / full_width;
  return shading;
}

std::array<int, 4> FindCorners(const std::vector<cv::Point>& contour, const ShadingImage& shading,
                               const BorderTest& on_border) {
  const auto is_fold = [&](const cv::Point& a, const cv::Point& b) {
    return detail::IsShadingStep(shading.grey, shading.mask, shading.scale, a, b);
  };
  // A fold's crease a little way from a page corner, along a side: sampled
  // close to the crease, as the panel beyond it may be narrow.
  const auto is_crease = [&](const cv::Point& a, const cv::Point& b) {
    return detail::IsShadingStep(shading.grey, shading.mask, shading.scale, a, b, 4.0);
  };
  return detail::MoveFoldEndsToPageCorners(
      contour,
      detail::MoveBorderCornersToPageCorners(contour, detail::FindCornerIndices(contour, is_fold),
                                             on_border),
      on_border, is_crease);
}

}  // namespace internal
}  // namespace docunfold::boundary
