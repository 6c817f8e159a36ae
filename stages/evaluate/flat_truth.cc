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
  return out;
}

}  // namespace docunfold::evaluate
