// LinesFromFlatScan (ground_truth.h): the true lines of a page read off its
// flat scan.
#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/statistics.h"
#include "stages/evaluate/ground_truth.h"

namespace docunfold::evaluate {
namespace {

// Rules along x (or, transposed, along y): runs of ink at least `min_length`
// long and at most `max_width` thick.
void AddRules(const cv::Mat1b& ink, bool transposed, double min_length, double max_width,
              std::vector<TrueLine>* out) {
  cv::Mat1b lines;
  cv::morphologyEx(ink, lines, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(int(min_length), 1)));
  cv::Mat1i labels, stats;
  cv::Mat1d centroids;
  const int n = cv::connectedComponentsWithStats(lines, labels, stats, centroids, 8);
  for (int i = 1; i < n; ++i) {
    const int w = stats(i, cv::CC_STAT_WIDTH), h = stats(i, cv::CC_STAT_HEIGHT);
    if (w < min_length || h > max_width) continue;
    const double x0 = stats(i, cv::CC_STAT_LEFT) - 0.5, x1 = x0 + w;
    const double y = centroids(i, 1);
    TrueLine line{"rule", {}};
    if (transposed)
      line.points = {{y, x0}, {y, x1}};
    else
      line.points = {{x0, y}, {x1, y}};
    out->push_back(line);
  }
}

// Pieces of text on one baseline (within a pixel), left to right, become one
// line across any blank gap between them, as synth's truth records a
// receipt's row ("Butter ....... 5.54" is one line): on the flat page they
// are one straight line. Not across a vertical rule.
std::vector<TrueLine> JoinRows(const std::vector<TrueLine>& lines) {
  std::vector<TrueLine> text, out;
  for (const TrueLine& l : lines) (l.kind == "text" ? text : out).push_back(l);
  std::sort(text.begin(), text.end(),
            [](const TrueLine& a, const TrueLine& b) { return a.points[0].y() < b.points[0].y(); });
  auto rule_across = [&](double x0, double x1, double y) {
    for (const TrueLine& r : out) {
      const Eigen::Vector2d& a = r.points.front();
      const Eigen::Vector2d& b = r.points.back();
      if (std::abs(a.x() - b.x()) > 1.0) continue;  // vertical rules only
      if (a.x() > x0 && a.x() < x1 && std::min(a.y(), b.y()) < y && std::max(a.y(), b.y()) > y - 5)
        return true;
    }
    return false;
  };
  // Rows: runs of pieces whose baselines lie within a pixel of the first's.
  std::vector<TrueLine> rows;
  for (size_t i = 0; i < text.size();) {
    size_t j = i;
    while (j < text.size() && text[j].points[0].y() - text[i].points[0].y() <= 1.0) ++j;
    std::vector<TrueLine> row(text.begin() + i, text.begin() + j);
    std::sort(row.begin(), row.end(), [](const TrueLine& a, const TrueLine& b) {
      return a.points[0].x() < b.points[0].x();
    });
    bool started = false;  // rows.back() is a line of this row
    for (const TrueLine& piece : row) {
      if (started &&
          !rule_across(rows.back().points[1].x(), piece.points[0].x(), piece.points[0].y())) {
        rows.back().points[1].x() = std::max(rows.back().points[1].x(), piece.points[1].x());
        continue;
      }
      rows.push_back(piece);
      started = true;
    }
    i = j;
  }
  out.insert(out.end(), rows.begin(), rows.end());
  return out;
}

}  // namespace

std::vector<TrueLine> LinesFromFlatScan(const GroundTruth& gt) {
  cv::Mat1b grey =
      cv::imread((gt.root / "ground_truth" / "flat.png").string(), cv::IMREAD_GRAYSCALE);
  std::vector<TrueLine> out;
  if (grey.empty()) return out;
  const cv::Mat1b ink = grey < 128;
  const double min_rule = 0.08 * std::min(grey.cols, grey.rows);
  AddRules(ink, false, min_rule, 6, &out);
  cv::Mat1b t;
  cv::transpose(ink, t);
  AddRules(t, true, min_rule, 6, &out);

  // Characters: small components; lines: characters whose vertical extents
  // overlap, chained left to right across gaps of at most two heights.
  cv::Mat1i labels, stats;
  cv::Mat1d centroids;
  const int n = cv::connectedComponentsWithStats(ink, labels, stats, centroids, 8);
  struct Char {
    double x0, x1, y0, y1;
  };
  std::vector<Char> chars;
  for (int i = 1; i < n; ++i) {
    const int w = stats(i, cv::CC_STAT_WIDTH), h = stats(i, cv::CC_STAT_HEIGHT);
    if (h < 5 || h > 60 || w > 80 || stats(i, cv::CC_STAT_AREA) < 8) continue;
    const double x0 = stats(i, cv::CC_STAT_LEFT), y0 = stats(i, cv::CC_STAT_TOP);
    chars.push_back({x0, x0 + w, y0, y0 + h});
  }
  std::sort(chars.begin(), chars.end(), [](const Char& a, const Char& b) { return a.x0 < b.x0; });
  std::vector<char> used(chars.size(), 0);
  for (size_t i = 0; i < chars.size(); ++i) {
    if (used[i]) continue;
    std::vector<size_t> line = {i};
    used[i] = 1;
    Char last = chars[i];
    for (size_t j = i + 1; j < chars.size(); ++j) {
      if (used[j]) continue;
      const Char& c = chars[j];
      const double h = std::max(last.y1 - last.y0, c.y1 - c.y0);
      if (c.x0 - last.x1 > 2.0 * h) {
        if (c.x0 - last.x1 > 10.0 * h) break;
        continue;
      }
      const double overlap = std::min(last.y1, c.y1) - std::max(last.y0, c.y0);
      if (overlap < 0.5 * std::min(last.y1 - last.y0, c.y1 - c.y0)) continue;
      line.push_back(j);
      used[j] = 1;
      last = c;
    }
    if (line.size() < 3) continue;
    std::vector<double> bottoms;
    double x0 = 1e300, x1 = -1e300;
    for (size_t k : line) {
      bottoms.push_back(chars[k].y1);
      x0 = std::min(x0, chars[k].x0);
      x1 = std::max(x1, chars[k].x1);
    }
    // Pixel centres at integers: the ink's bottom edge is y1 - 0.5.
    const double y = Median(bottoms) - 0.5;
    out.push_back({"text", {{x0 - 0.5, y}, {x1 - 0.5, y}}});
  }
  // A till roll (at least twice as long as wide) prints a row as one line,
  // as synth's receipts record it; a table's cells are lines of their own,
  // as synth's tables record them.
  const bool roll = std::max(grey.cols, grey.rows) >= 2 * std::min(grey.cols, grey.rows);
  return roll ? JoinRows(out) : out;
}

}  // namespace docunfold::evaluate
