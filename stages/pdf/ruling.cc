#include "stages/pdf/ruling.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace docunfold::pdf {
namespace {

// The thin components of `print` opened by a line `length` pixels long
// (across or down), added to `rules`.
void AddRules(const cv::Mat& print, bool across, int length, double max_thickness, cv::Mat& rules) {
  const cv::Mat line =
      cv::getStructuringElement(cv::MORPH_RECT, across ? cv::Size(length, 1) : cv::Size(1, length));
  cv::Mat opened;
  cv::morphologyEx(print, opened, cv::MORPH_OPEN, line);
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(opened, labels, stats, centroids, 8, CV_32S);
  std::vector<uchar> thin(count, 0);
  for (int i = 1; i < count; ++i) {
    const int along = stats.at<int>(i, across ? cv::CC_STAT_WIDTH : cv::CC_STAT_HEIGHT);
    thin[i] = stats.at<int>(i, cv::CC_STAT_AREA) <= max_thickness * along;
  }
  for (int y = 0; y < labels.rows; ++y) {
    const int* label = labels.ptr<int>(y);
    uchar* rule = rules.ptr<uchar>(y);
    for (int x = 0; x < labels.cols; ++x)
      if (thin[label[x]]) rule[x] = 255;
  }
}

}  // namespace

Ruling WithoutRuling(const cv::Mat& page, const RulingOptions& o) {
  const cv::Mat print = PrintPixels(page, o.print);
  const int long_side = std::max(page.cols, page.rows);
  const double max_thickness =
      std::max(o.min_thickness_px, o.max_thickness_of_long_side * long_side);
  const int min_length = std::max(2, int(o.min_length_of_long_side * long_side));
  cv::Mat rules = cv::Mat::zeros(page.size(), CV_8U);
  AddRules(print, true, min_length, max_thickness, rules);
  AddRules(print, false, min_length, max_thickness, rules);

  Ruling r;
  if (cv::countNonZero(rules) == 0) {
    r.page = page;
    return r;
  }
  const int grow = 2 * o.margin_px + 1;
  cv::dilate(rules, rules, cv::getStructuringElement(cv::MORPH_RECT, {grow, grow}));
  const int reach = 2 * o.paper_radius_px + 1;
  cv::Mat paper;
  cv::dilate(page, paper, cv::getStructuringElement(cv::MORPH_RECT, {reach, reach}));
  r.page = page.clone();
  paper.copyTo(r.page, rules);
  r.rule_share = double(cv::countNonZero(rules)) / rules.total();
  return r;
}

}  // namespace docunfold::pdf
