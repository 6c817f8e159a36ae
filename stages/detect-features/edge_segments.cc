// Edge segments: centre lines of thin dark lines (table rules, boxes) from
// pairs of LSD edges, away from the region's outline and from characters.
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <opencv2/imgproc.hpp>

#include "common/program.h"
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
      if (k - 1 - first > best_last - best_first) {
        best_first = first;
        best_last = k - 1;
      }
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

// A centre line found between two LSD edges.
struct Piece {
  cv::Point2d a, b;
  bool joined = false;                                     // taken into another piece
  std::vector<std::pair<cv::Point2d, cv::Point2d>> parts;  // as found, when joined
};

// LSD ends an edge wherever another line crosses it, so a table's column
// rules come out as pieces one row high, each too short to keep. Joins the
// centre lines of pieces of one straight rule (parallel within 2 degrees,
// every end within `max_offset` px of the joined line) across gaps up to
// `max_gap` px. A curved rule stays in pieces that are straight.
std::vector<Piece> JoinCollinear(std::vector<Piece> pieces, double max_gap, double max_offset) {
  const double max_sin = std::sin(2.0 * CV_PI / 180);
  auto offset = [](const cv::Point2d& a, const cv::Point2d& b, const cv::Point2d& p) {
    const cv::Point2d d = b - a;
    return std::abs(d.x * (p.y - a.y) - d.y * (p.x - a.x)) / cv::norm(d);
  };
  for (bool joined = true; joined;) {
    joined = false;
    for (size_t i = 0; i < pieces.size(); ++i) {
      Piece& s = pieces[i];
      if (s.joined) continue;
      for (size_t j = 0; j < pieces.size(); ++j) {
        const Piece& t = pieces[j];
        if (j == i || t.joined) continue;
        const double length = cv::norm(s.b - s.a);
        const cv::Point2d dir = (s.b - s.a) * (1.0 / length);
        const cv::Point2d t_dir = (t.b - t.a) * (1.0 / cv::norm(t.b - t.a));
        if (std::abs(dir.x * t_dir.y - dir.y * t_dir.x) > max_sin) continue;
        if (offset(s.a, s.b, t.a) > max_offset || offset(s.a, s.b, t.b) > max_offset) continue;
        const double ua = (t.a - s.a).dot(dir), ub = (t.b - s.a).dot(dir);
        const double u0 = std::min(ua, ub), u1 = std::max(ua, ub);
        if (std::max(u0 - length, -u1) > max_gap) continue;
        // The joined piece runs between the outermost ends.
        const cv::Point2d a = u0 < 0 ? (ua < ub ? t.a : t.b) : s.a;
        const cv::Point2d b = u1 > length ? (ua > ub ? t.a : t.b) : s.b;
        if (cv::norm(b - a) < length) continue;
        if (offset(a, b, s.a) > max_offset || offset(a, b, s.b) > max_offset ||
            offset(a, b, t.a) > max_offset || offset(a, b, t.b) > max_offset)
          continue;
        if (s.parts.empty()) s.parts.push_back({s.a, s.b});
        if (t.parts.empty()) s.parts.push_back({t.a, t.b});
        s.parts.insert(s.parts.end(), t.parts.begin(), t.parts.end());
        s.a = a;
        s.b = b;
        pieces[j].joined = true;
        joined = true;
      }
    }
  }
  std::vector<Piece> kept;
  for (const Piece& p : pieces)
    if (!p.joined) kept.push_back(p);
  return kept;
}

// Pieces shorter than this (px) are pixel noise even where a gap is bridged.
constexpr double kShortestPiece = 4.0;

// Step 1: LSD's line segments in `grey` (its pixels). LSD smooths before it
// looks for gradients, which wipes out rules one pixel wide (a table's
// column rules, seen obliquely): with small text it runs on the region's box
// enlarged.
std::vector<cv::Vec4f> DetectLsdLines(const cv::Mat1b& grey, const cv::Mat1b& region,
                                      const TextResult& text, const FeaturesOptions& options) {
  std::vector<cv::Vec4f> lines;
  cv::Ptr<cv::LineSegmentDetector> lsd = cv::createLineSegmentDetector(cv::LSD_REFINE_STD);
  const cv::Rect box = cv::boundingRect(region) & cv::Rect(0, 0, grey.cols, grey.rows);
  double upscale = options.lsd_upscale;
  if (upscale <= 0) upscale = text.height > 0 && text.height < 12 && box.area() <= 4e6 ? 2 : 1;
  if (upscale > 1 && !box.empty()) {
    cv::Mat1b enlarged;
    cv::resize(grey(box), enlarged, cv::Size(), upscale, upscale, cv::INTER_CUBIC);
    lsd->detect(enlarged, lines);
    for (cv::Vec4f& l : lines)
      for (int k = 0; k < 4; k += 2) {
        // Pixel centres: enlarged u is at (u + 0.5) / upscale - 0.5.
        l[k] = float((l[k] + 0.5) / upscale - 0.5 + box.x);
        l[k + 1] = float((l[k + 1] + 0.5) / upscale - 0.5 + box.y);
      }
  } else {
    lsd->detect(grey, lines);
  }
  return lines;
}

// Step 2: the LSD lines as edges: clipped to the region, at least
// kShortestPiece long, their normal towards the darker side; longest first.
std::vector<Edge> RegionEdges(const std::vector<cv::Vec4f>& lines, const cv::Mat1b& grey,
                              const cv::Mat1b& region) {
  std::vector<Edge> edges;
  for (const cv::Vec4f& l : lines) {
    Edge e;
    e.a = {l[0], l[1]};
    e.b = {l[2], l[3]};
    if (!ClipToRegion(region, &e.a, &e.b)) continue;
    e.length = cv::norm(e.b - e.a);
    if (e.length < kShortestPiece) continue;
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
  return edges;
}

// Whether the line a-b (of `length` px) runs along printed ink: none (a
// faint rule), or one component that is not a character and is line-like
// (long and thin, or a large grid).
bool AlongPrintedLine(const cv::Mat1b& ink, const InkComponents& components, const TextResult& text,
                      const cv::Point2d& a, const cv::Point2d& b, double length) {
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
    if (n > best_votes) {
      best = label;
      best_votes = n;
    }
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
}

using LineTest = std::function<bool(const cv::Point2d&, const cv::Point2d&, double)>;

// What pairing the edges found.
struct Pairing {
  std::vector<Piece> pieces;  // centre lines of thin dark lines, as found
  int paired = 0;             // pairs of edges
  int rejected = 0;           // ... of them not along a printed line
};

// Step 3: the centre lines between pairs of edges (the two sides of one thin
// dark line, at most `max_width` apart) that run along printed ink; marks
// the edges used. First the edges `min_length` long, which give a segment on
// their own, then (when joining) the pieces, so that a piece never takes a
// long edge's partner.
Pairing PairEdges(std::vector<Edge>& edges, double min_length, double max_width,
                  const FeaturesOptions& options, const LineTest& along_printed_line) {
  Pairing pairing;
  std::vector<Piece>& pieces = pairing.pieces;
  // Where t lies along s: the range of s (distances from s.a) it overlaps.
  auto overlap_along = [](const Edge& s, const Edge& t) {
    const double ua = (t.a - s.a).dot(s.dir), ub = (t.b - s.a).dot(s.dir);
    return std::pair(std::max(0.0, std::min(ua, ub)), std::min(s.length, std::max(ua, ub)));
  };
  std::vector<double> shortest{min_length};
  if (options.join_gap > 0) shortest.push_back(kShortestPiece);
  for (const double shortest_edge : shortest)
    for (size_t i = 0; i < edges.size(); ++i) {
      Edge& s = edges[i];
      if (s.used || s.length < shortest_edge) continue;
      // Its partner: the other side of the same dark line, parallel, close,
      // dark side facing this one, overlapping along it.
      int partner = -1;
      double best_overlap = 0;
      for (size_t j = 0; j < edges.size(); ++j) {
        if (j == i || edges[j].used || edges[j].length < shortest_edge) continue;
        const Edge& t = edges[j];
        if (std::abs(s.dir.x * t.dir.y - s.dir.y * t.dir.x) > std::sin(4.0 * CV_PI / 180)) continue;
        const cv::Point2d tm = 0.5 * (t.a + t.b);
        const double offset = (tm - s.a).dot(s.normal);  // > 0: on s's dark side
        if (offset < 0.5 || offset > max_width) continue;
        if (t.normal.dot(s.normal) > -0.9) continue;  // dark sides face each other
        const auto [u0, u1] = overlap_along(s, t);
        const double overlap = u1 - u0;
        if (overlap < 0.5 * std::min(s.length, t.length)) continue;
        if (overlap > best_overlap) {
          best_overlap = overlap;
          partner = int(j);
        }
      }
      if (partner >= 0) {
        const Edge& t = edges[size_t(partner)];
        const auto [u0, u1] = overlap_along(s, t);
        // Centre line: halfway between s and t's line, over their overlap.
        const cv::Point2d tn(-t.dir.y, t.dir.x);
        auto midpoint = [&](double u) {
          const cv::Point2d p = s.a + s.dir * u;
          const double dist = (p - t.a).dot(tn);  // signed distance to t's line
          return p - tn * (0.5 * dist);
        };
        const cv::Point2d p0 = midpoint(u0), p1 = midpoint(u1);
        ++pairing.paired;
        if (cv::norm(p1 - p0) >= std::max(shortest_edge, kShortestPiece) &&
            along_printed_line(p0, p1, cv::norm(p1 - p0))) {
          pieces.push_back({p0, p1, false, {}});
          s.used = true;
          edges[size_t(partner)].used = true;
          continue;
        }
        ++pairing.rejected;
      }
    }
  return pairing;
}

}  // namespace

std::vector<Segment> DetectEdgeSegments(const cv::Mat1b& grey, const cv::Mat1b& ink,
                                        const InkComponents& components, const TextResult& text,
                                        const cv::Mat1b& region, const FeaturesOptions& options) {
  const std::vector<cv::Vec4f> lines = DetectLsdLines(grey, region, text, options);
  // Character strokes are shorter than a few text heights.
  const double min_length =
      std::max(options.min_length_px, text.height > 0 ? 3.0 * text.height : 0.0);
  const double max_width = std::max(4.0, 0.6 * text.height);
  std::vector<Edge> edges = RegionEdges(lines, grey, region);

  std::vector<Segment> out;
  const LineTest along_printed_line = [&](const cv::Point2d& a, const cv::Point2d& b,
                                          double length) {
    return AlongPrintedLine(ink, components, text, a, b, length);
  };
  Pairing pairing = PairEdges(edges, min_length, max_width, options, along_printed_line);
  std::vector<Piece>& pieces = pairing.pieces;
  if (options.step_edges)
    for (Edge& s : edges)
      if (!s.used && s.length >= min_length) {
        out.push_back({"edge", {s.a, s.b}, 0});
        s.used = true;
      }
  const size_t paired_pieces = pieces.size();
  if (options.join_gap > 0) {
    const double max_gap = std::max(options.join_gap, text.height > 0 ? 0.5 * text.height : 0.0);
    pieces = JoinCollinear(std::move(pieces), max_gap, 1.0);
  }
  int kept_lines = 0;
  // Every piece ran along a printed line when it was paired; a joined line
  // must do so as a whole, and where it does not, its pieces stand as found.
  auto keep = [&](const cv::Point2d& a, const cv::Point2d& b, bool joined) {
    const double length = cv::norm(b - a);
    if (length < min_length || (joined && !along_printed_line(a, b, length))) return false;
    out.push_back({"edge", {a, b}, 0});
    ++kept_lines;
    return true;
  };
  for (const Piece& p : pieces)
    if (!keep(p.a, p.b, !p.parts.empty()))
      for (const auto& [a, b] : p.parts) keep(a, b, false);
  if (options.verbose)
    Log("LSD: " + std::to_string(lines.size()) + " edges, " + std::to_string(edges.size()) +
        " inside the region, " + std::to_string(paired_pieces) + " lines between them, " +
        std::to_string(pieces.size()) + " after joining, " + std::to_string(kept_lines) +
        " long enough; " + std::to_string(pairing.paired) + " pairs, " +
        std::to_string(pairing.rejected) + " of them not along a printed line");
  return out;
}

}  // namespace docunfold::features::detail
