#include "stages/pdf/contrast.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace docunfold::pdf {
namespace {

// The histogram (256 bins) of the pixels of `grey` under `mask` (all where
// empty).
cv::Mat GreyHistogram(const cv::Mat& grey, const cv::Mat& mask) {
  const int channels[] = {0};
  const int bins[] = {256};
  const float range[] = {0, 256};
  const float* ranges[] = {range};
  cv::Mat histogram;
  cv::calcHist(&grey, 1, channels, mask, histogram, 1, bins, ranges);
  return histogram;
}

// The grey level that `share` (0..1) of the pixels counted in `histogram`
// are darker than.
double GreyQuantile(const cv::Mat& histogram, double share) {
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
  const cv::Mat grey = Grey(page);
  if (grey.empty()) return grey.clone();
  const cv::Mat print = PrintPixels(grey, o.print);
  const cv::Mat histogram = GreyHistogram(grey, cv::Mat());
  double black = GreyQuantile(histogram, o.black_percentile / 100);
  if (cv::countNonZero(print) > 0)
    black = std::min(black, GreyQuantile(GreyHistogram(grey, print), 0.5));
  const double white = GreyQuantile(histogram, 0.5);
  // A copy: never the caller's own pixels.
  if (white - black < o.min_range) return grey.clone();
  cv::Mat out;
  grey.convertTo(out, CV_8U, 255 / (white - black), -black * 255 / (white - black));
  return out;
}

}  // namespace docunfold::pdf
