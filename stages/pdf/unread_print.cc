#include "stages/pdf/unread_print.h"

#include <algorithm>
#include <cctype>
#include <opencv2/imgproc.hpp>

namespace docunfold::pdf {

cv::Mat Grey(const cv::Mat& page) {
  if (page.channels() != 3) return page;
  cv::Mat grey;
  cv::cvtColor(page, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

cv::Mat PrintPixels(const cv::Mat& page, const PrintThreshold& t) {
  cv::Mat print;
  cv::adaptiveThreshold(Grey(page), print, 255, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY_INV,
                        t.window_px | 1, t.contrast);
  return print;
}

double UnreadPrint(const cv::Mat& page, const std::vector<Word>& words,
                   const UnreadPrintOptions& o) {
  const cv::Mat dark = PrintPixels(page, o.print);
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(dark, labels, stats, centroids, 8, CV_32S);
  std::vector<uchar> glyph(count, 0);
  for (int i = 1; i < count; ++i)
    glyph[i] = stats.at<int>(i, cv::CC_STAT_HEIGHT) < o.max_height_of_page * page.rows &&
               stats.at<int>(i, cv::CC_STAT_WIDTH) < o.max_width_of_page * page.cols &&
               stats.at<int>(i, cv::CC_STAT_AREA) >= o.min_area_px;

  cv::Mat covered = cv::Mat::zeros(page.size(), CV_8U);
  const cv::Rect whole(0, 0, page.cols, page.rows);
  for (const Word& w : words) {
    if (std::all_of(w.text.begin(), w.text.end(), [](unsigned char c) { return std::isspace(c); }))
      continue;
    const cv::Rect grown(w.box.x - o.margin_px, w.box.y - o.margin_px,
                         w.box.width + 2 * o.margin_px, w.box.height + 2 * o.margin_px);
    covered(grown & whole).setTo(255);
  }
  const int border = int(o.border_of_short_side * std::min(page.rows, page.cols));
  size_t print = 0, unread = 0;
  for (int y = border; y < page.rows - border; ++y) {
    const int* label = labels.ptr<int>(y);
    const uchar* cover = covered.ptr<uchar>(y);
    for (int x = border; x < page.cols - border; ++x) {
      if (!glyph[label[x]]) continue;
      ++print;
      unread += cover[x] == 0;
    }
  }
  return print == 0 ? 0 : double(unread) / print;
}

}  // namespace docunfold::pdf
