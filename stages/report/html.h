// Small pieces of a self-contained HTML page: images inlined as data: URIs
// and an inline SVG scatter plot (text is escaped by common/markup.h).
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/markup.h"

namespace docunfold::report {

std::string Base64(const std::vector<unsigned char>& bytes);

// <img> with the image encoded inline (JPEG unless `png`), scaled to at most
// `max_width` pixels wide first.
std::string InlineImage(const cv::Mat& image, int max_width, const std::string& alt,
                        bool png = false);

struct PlotPoint {
  double x = 0, y = 0;
  int series = 0;  // colour index
};

struct PlotOptions {
  int width = 640, height = 320;
  std::string x_label, y_label;
  bool log_y = false;
  std::vector<std::string> series_names;
};

// Inline <svg> scatter plot with axes, ticks and a legend.
std::string SvgScatter(const std::vector<PlotPoint>& points, const PlotOptions& options);

}  // namespace docunfold::report
