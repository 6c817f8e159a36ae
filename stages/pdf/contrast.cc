#include "stages/pdf/contrast.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace docunfold::pdf {
namespace {

// The grey level that `share` (0..1) of the pixels of `grey` under `mask`
// (all where empty) are darker than.
double GreyQuantile(const cv::Mat& grey, const cv::Mat& mask, double share) {
  const int channels[] = {0};
  const int bins[] = {256};
  const float range[] = {0, 256};
  const float* ranges[] = {range};
  cv::Mat histogram;
  cv::calcHist(&grey, 1, channels, mask, histogram, 1, bins, ranges);
  const double total = cv::sum(histogram)[0];
  double below = 0;
  for (int level = 0; level < 256; ++level) {
    below += histogram.at<float>(level);
    if (below > share * total) return level;
  }
  return 255;
}

}  // namespace

cv::Mat PrintStretchedToBlack(const cv::Mat& page, const ContrastOptions& o) {
  cv::Mat grey;
  if (page.channels() == 3)
    cv::cvtColor(page, grey, cv::COLOR_BGR2GRAY);
  else
    grey = page.clone();
  if (grey.empty()) return grey;
  const cv::Mat print = PrintPixels(grey, o.print);
  double black = GreyQuantile(grey, cv::Mat(), o.black_percentile / 100);
  if (cv::countNonZero(print) > 0) black = std::min(black, GreyQuantile(grey, print, 0.5));
  const double white = GreyQuantile(grey, cv::Mat(), 0.5);
  if (white - black < o.min_range) return grey;
  cv::Mat out;
  grey.convertTo(out, CV_8U, 255 / (white - black), -black * 255 / (white - black));
  return out;
}

}  // namespace docunfold::pdf
