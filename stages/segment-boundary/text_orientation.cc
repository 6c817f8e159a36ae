#include "stages/segment-boundary/text_orientation.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/statistics.h"

namespace docunfold::boundary {
namespace {

struct Votes {
  int up = 0;
  int down = 0;
};

// Votes of the text lines of `ink` (text running along x): in narrow vertical
// strips, each line's row profile has a dense core (the x-height band); a line
// votes up when clearly more of its ink lies above the core than below.
Votes ProfileVotes(const cv::Mat1b& ink, double char_height) {
  Votes v;
  const int strip = std::max(16, int(std::lround(5 * char_height)));
  std::vector<int> profile(ink.rows);
  for (int x0 = 0; x0 + strip / 2 < ink.cols; x0 += strip) {
    const int x1 = std::min(ink.cols, x0 + strip);
    for (int y = 0; y < ink.rows; ++y) profile[y] = cv::countNonZero(ink.row(y).colRange(x0, x1));
    for (int y = 0; y < ink.rows;) {
      if (profile[y] == 0) {
        ++y;
        continue;
      }
      int end = y;
      while (end < ink.rows && profile[end] > 0) ++end;
      const int height = end - y;
      if (height >= 0.6 * char_height && height <= 2.5 * char_height) {
        const int peak = *std::max_element(profile.begin() + y, profile.begin() + end);
        int core0 = y, core1 = end - 1;
        while (profile[core0] < 0.5 * peak) ++core0;
        while (profile[core1] < 0.5 * peak) --core1;
        double above = 0, below = 0, total = 0;
        for (int k = y; k < end; ++k) {
          total += profile[k];
          if (k < core0) above += profile[k];
          if (k > core1) below += profile[k];
        }
        // A clear difference only: digits and capitals alone have none.
        if (above > 1.5 * below && above > 0.08 * total) ++v.up;
        if (below > 1.5 * above && below > 0.08 * total) ++v.down;
      }
      y = end;
    }
  }
  return v;
}

}  // namespace

TextOrientation EstimateTextTopSide(const cv::Mat3b& image, const cv::Mat1b& mask,
                                    const std::array<cv::Point2d, 4>& c) {
  TextOrientation out;
  // 1. The page as a rectangle (a homography from its corners; folds and
  //    curls only bend the text lines a little).
  const double w = 0.5 * (cv::norm(c[1] - c[0]) + cv::norm(c[2] - c[3]));
  const double h = 0.5 * (cv::norm(c[3] - c[0]) + cv::norm(c[2] - c[1]));
  const double scale = std::min(1.0, 2000.0 / std::max(w, h));
  const int W = std::max(8, int(w * scale)), H = std::max(8, int(h * scale));
  std::vector<cv::Point2f> src(c.begin(), c.end());
  std::vector<cv::Point2f> dst = {
      {0, 0}, {float(W - 1), 0}, {float(W - 1), float(H - 1)}, {0, float(H - 1)}};
  const cv::Mat homography = cv::getPerspectiveTransform(src, dst);
  cv::Mat1b grey, page, region;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  cv::warpPerspective(grey, page, homography, cv::Size(W, H), cv::INTER_LINEAR,
                      cv::BORDER_REPLICATE);
  cv::warpPerspective(mask, region, homography, cv::Size(W, H), cv::INTER_NEAREST);
  const int margin = std::max(3, int(0.02 * std::min(W, H)));
  cv::erode(region, region,
            cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * margin + 1, 2 * margin + 1)));

  // 2. Ink: darker than its surroundings, as characters are.
  cv::Mat1b ink;
  const int block = std::max(15, int(0.03 * std::max(W, H)) | 1);
  cv::adaptiveThreshold(page, ink, 255, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY_INV, block,
                        12);
  ink &= region;

  // 3. Character-sized components only.
  cv::Mat1i labels, stats;
  cv::Mat1d centroids;
  const int n = cv::connectedComponentsWithStats(ink, labels, stats, centroids, 8);
  std::vector<int> heights;
  std::vector<int> keep(n, 0);
  const int max_size = std::max(12, int(0.04 * std::max(W, H)));
  for (int i = 1; i < n; ++i) {
    const int cw = stats(i, cv::CC_STAT_WIDTH), ch = stats(i, cv::CC_STAT_HEIGHT);
    const int area = stats(i, cv::CC_STAT_AREA);
    if (area < 5 || std::max(cw, ch) < 3 || ch > max_size || cw > 8 * max_size) continue;
    keep[i] = 1;
    heights.push_back(ch);
  }
  if (heights.size() < 30) {
    out.why = "too few character-like marks (" + std::to_string(heights.size()) + ")";
    return out;
  }
  const double char_size = NthSmallest(heights, heights.size() / 2);
  cv::Mat1b text = cv::Mat1b::zeros(ink.size());
  for (int y = 0; y < ink.rows; ++y)
    for (int x = 0; x < ink.cols; ++x)
      if (keep[labels(y, x)]) text(y, x) = 255;

  // 4. Do the lines run along x or along y? Votes of each character's nearest
  //    neighbour direction.
  std::vector<cv::Point2d> centres;
  for (int i = 1; i < n; ++i)
    if (keep[i]) centres.emplace_back(centroids(i, 0), centroids(i, 1));
  std::vector<int> order(centres.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = int(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return centres[a].x < centres[b].x; });
  int along_x = 0, along_y = 0;
  const double reach = 4 * char_size;
  for (size_t oi = 0; oi < order.size(); ++oi) {
    const cv::Point2d p = centres[order[oi]];
    double best = reach * reach;
    cv::Point2d best_d(0, 0);
    for (int dir : {-1, 1})
      for (long oj = long(oi) + dir; oj >= 0 && oj < long(order.size()); oj += dir) {
        const cv::Point2d d = centres[order[oj]] - p;
        if (std::abs(d.x) > reach) break;
        const double d2 = d.dot(d);
        if (d2 < best && d2 > 0) {
          best = d2;
          best_d = d;
        }
      }
    if (best_d == cv::Point2d(0, 0)) continue;
    const double ax = std::abs(best_d.x), ay = std::abs(best_d.y);
    if (ax > 2 * ay)
      ++along_x;
    else if (ay > 2 * ax)
      ++along_y;
  }
  const bool horizontal = along_x >= along_y;

  // 5. Up or down along the perpendicular.
  Votes v;
  if (horizontal) {
    v = ProfileVotes(text, char_size);
  } else {
    cv::Mat1b t;
    cv::transpose(text, t);  // x' = y: the top of t is the page's left side
    v = ProfileVotes(t, char_size);
  }
  out.votes = v.up + v.down;
  out.confidence = out.votes > 0 ? double(std::max(v.up, v.down)) / out.votes : 0.0;
  // Decide only on a clear majority: three standard deviations of a fair
  // coin's count (single lines vote wrongly often; see
  // docs/decisions/segment-boundary.md, "Text orientation by a clear majority").
  const double lead = std::abs(v.up - v.down);
  if (out.votes < 10 || lead < 3.0 * std::sqrt(double(out.votes))) {
    out.why = "text lines do not agree clearly (" + std::to_string(v.up) + " up, " +
              std::to_string(v.down) + " down)";
    return out;
  }
  // Side i runs from corner i to i+1: 0 is y = 0 of the rectangle, 1 is
  // x = W-1, 2 is y = H-1, 3 is x = 0.
  if (horizontal)
    out.top_side = v.up > v.down ? 0 : 2;
  else
    out.top_side = v.up > v.down ? 3 : 1;
  return out;
}

}  // namespace docunfold::boundary
