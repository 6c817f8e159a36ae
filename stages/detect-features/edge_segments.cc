// Edge segments: centre lines of thin dark lines (table rules, boxes) from
// pairs of LSD edges, away from the region's outline and from characters.
#include <algorithm>
#include <cmath>
#include <map>

#include <opencv2/imgproc.hpp>

#include "common/cli.h"
#include "stages/detect-features/feature_parts.h"

namespace docunfold::features::detail {
namespace {

struct Edge {
  cv::Point2d a, b;
  cv::Point2d dir;     // unit, a -> b
  cv::Point2d normal;  // unit, towards the darker side
  double length = 0;
  bool used = false;
};

float Sample(const cv::Mat1b& grey, const cv::Point2d& p) {
  const int x = std::clamp(int(std::lround(p.x)), 0, grey.cols - 1);
  const int y = std::clamp(int(std::lround(p.y)), 0, grey.rows - 1);
  return grey(y, x);
}

// The longest stretch of a -> b inside the region (about every 2 px), or
// false when there is none.
bool ClipToRegion(const cv::Mat1b& region, cv::Point2d* a, cv::Point2d* b) {
  const int steps = std::max(1, int(cv::norm(*b - *a) / 2.0));
  int best_first = -1, best_last = -1, first = -1;
  for (int k = 0; k <= steps + 1; ++k) {
    bool inside = false;
    if (k <= steps) {
      const cv::Point2d p = *a + (*b - *a) * (double(k) / steps);
      const int x = int(std::lround(p.x)), y = int(std::lround(p.y));
      inside = x >= 0 && y >= 0 && x < region.cols && y < region.rows && region(y, x);
    }
    if (inside && first < 0) first = k;
    if (!inside && first >= 0) {
      if (k - 1 - first > best_last - best_first) { best_first = first; best_last = k - 1; }
      first = -1;
    }
  }
  if (best_first < 0 || best_last <= best_first) return false;
  const cv::Point2d d = *b - *a;
  const cv::Point2d start = *a;
  *a = start + d * (double(best_first) / steps);
  *b = start + d * (double(best_last) / steps);
  return true;
}

}  // namespace

std::vector<Segment> DetectEdgeSegments(const cv::Mat1b& grey, const cv::Mat1b& ink,
                                        const InkComponents& components,
                                        const TextResult& text, const cv::Mat1b& region,
                                        const FeaturesOptions& options) {
  std::vector<cv::Vec4f> lines;
  cv::Ptr<cv::LineSegmentDetector> lsd = cv::createLineSegmentDetector(cv::LSD_REFINE_STD);
  lsd->detect(grey, lines);
  // Character strokes are shorter than a few text heights.
  const double min_length =
      std::max(options.min_length_px, text.height > 0 ? 3.0 * text.height : 0.0);
  const double max_width = std::max(4.0, 0.6 * text.height);
  std::vector<Edge> edges;
  for (const cv::Vec4f& l : lines) {
    Edge e;
    e.a = {l[0], l[1]};
    e.b = {l[2], l[3]};
    if (!ClipToRegion(region, &e.a, &e.b)) continue;
    e.length = cv::norm(e.b - e.a);
    if (e.length < min_length) continue;
    e.dir = (e.b - e.a) * (1.0 / e.length);
    e.normal = {-e.dir.y, e.dir.x};
    // Which side is darker, a little off the middle of the edge.
    const cv::Point2d mid = 0.5 * (e.a + e.b);
    double left = 0, right = 0;
    for (double t : {-0.25, 0.0, 0.25}) {
      const cv::Point2d p = mid + e.dir * (t * e.length);
      left += Sample(grey, p + 1.5 * e.normal);
      right += Sample(grey, p - 1.5 * e.normal);
    }
    if (left > right) e.normal = -e.normal;
    edges.push_back(e);
  }
  std::sort(edges.begin(), edges.end(),
            [](const Edge& p, const Edge& q) { return p.length > q.length; });

  std::vector<Segment> out;
  // The ink a line runs along: none (a faint rule), or one component that
  // is not a character and is line-like (long and thin, or a large grid).
  auto along_printed_line = [&](const cv::Point2d& a, const cv::Point2d& b, double length) {
    std::map<int, int> votes;
    const int steps = std::max(2, int(length / 3.0));
    for (int k = 0; k <= steps; ++k) {
      const cv::Point2d p = a + (b - a) * (double(k) / steps);
      const int x = int(std::lround(p.x)), y = int(std::lround(p.y));
      int label = 0;
      for (int dy = -1; dy <= 1 && !label; ++dy)
        for (int dx = -1; dx <= 1 && !label; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx >= 0 && yy >= 0 && xx < ink.cols && yy < ink.rows && ink(yy, xx))
            label = components.labels(yy, xx);
        }
      ++votes[label];
    }
    int best = 0, best_votes = 0;
    for (auto [label, n] : votes)
      if (n > best_votes) { best = label; best_votes = n; }
    // A faint rule may be too light to count as ink; text never is.
    if (best == 0) return true;
    if (best_votes < 0.8 * (steps + 1)) return false;
    if (best < int(text.is_character.size()) && text.is_character[size_t(best)]) return false;
    // Longer than the line found (a grid, a frame), or thin: for a line of
    // length L and width w the box's diagonal is about L and the area L w,
    // so diagonal^2 / area is about L / w, whatever the line's slant.
    const double w = components.stats(best, cv::CC_STAT_WIDTH);
    const double h = components.stats(best, cv::CC_STAT_HEIGHT);
    const double area = components.stats(best, cv::CC_STAT_AREA);
    const double diagonal = std::hypot(w, h);
    return diagonal >= 1.5 * length || diagonal * diagonal / area >= 10.0;
  };

  int paired = 0, rejected = 0;
  for (size_t i = 0; i < edges.size(); ++i) {
    Edge& s = edges[i];
    if (s.used) continue;
    // Its partner: the other side of the same dark line, parallel, close,
    // dark side facing this one, overlapping along it.
    int partner = -1;
    double best_overlap = 0;
    for (size_t j = 0; j < edges.size(); ++j) {
      if (j == i || edges[j].used) continue;
      const Edge& t = edges[j];
      if (std::abs(s.dir.x * t.dir.y - s.dir.y * t.dir.x) > std::sin(4.0 * CV_PI / 180)) continue;
      const cv::Point2d tm = 0.5 * (t.a + t.b);
      const double offset = (tm - s.a).dot(s.normal);  // > 0: on s's dark side
      if (offset < 0.5 || offset > max_width) continue;
      if (t.normal.dot(s.normal) > -0.9) continue;  // dark sides face each other
      const double u0 = std::max(0.0, std::min((t.a - s.a).dot(s.dir), (t.b - s.a).dot(s.dir)));
      const double u1 = std::min(s.length, std::max((t.a - s.a).dot(s.dir), (t.b - s.a).dot(s.dir)));
      const double overlap = u1 - u0;
      if (overlap < 0.5 * std::min(s.length, t.length)) continue;
      if (overlap > best_overlap) { best_overlap = overlap; partner = int(j); }
    }
    if (partner >= 0) {
      const Edge& t = edges[size_t(partner)];
      const double u0 = std::max(0.0, std::min((t.a - s.a).dot(s.dir), (t.b - s.a).dot(s.dir)));
      const double u1 = std::min(s.length, std::max((t.a - s.a).dot(s.dir), (t.b - s.a).dot(s.dir)));
      // Centre line: halfway between s and t's line, over their overlap.
      const cv::Point2d tn(-t.dir.y, t.dir.x);
      auto midpoint = [&](double u) {
        const cv::Point2d p = s.a + s.dir * u;
        const double dist = (p - t.a).dot(tn);  // signed distance to t's line
        return p - tn * (0.5 * dist);
      };
      const cv::Point2d p0 = midpoint(u0), p1 = midpoint(u1);
      ++paired;
      if (cv::norm(p1 - p0) >= min_length && along_printed_line(p0, p1, cv::norm(p1 - p0))) {
        out.push_back({"edge", {p0, p1}, 0});
        s.used = true;
        edges[size_t(partner)].used = true;
        continue;
      }
      ++rejected;
    }
    if (options.step_edges) {
      out.push_back({"edge", {s.a, s.b}, 0});
      s.used = true;
    }
  }
  if (options.verbose)
    Log("LSD: " + std::to_string(lines.size()) + " edges, " + std::to_string(edges.size()) +
        " long enough inside the region, " + std::to_string(paired) + " pairs, " +
        std::to_string(rejected) + " of them not along a printed line");
  return out;
}

}  // namespace docunfold::features::detail
