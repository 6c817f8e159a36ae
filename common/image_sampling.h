// Reading an image between its pixels. Pixel centres are at integer
// coordinates, as everywhere in docunfold.
#pragma once

#include <algorithm>
#include <opencv2/core.hpp>

namespace docunfold {

// Bilinear interpolation of `m` at (x, y); outside the image, the value at
// the nearest point of its border.
template <typename T>
T SampleBilinear(const cv::Mat_<T>& m, double x, double y) {
  x = std::clamp(x, 0.0, m.cols - 1.0);
  y = std::clamp(y, 0.0, m.rows - 1.0);
  const int x0 = std::min(int(x), m.cols - 2 < 0 ? 0 : m.cols - 2);
  const int y0 = std::min(int(y), m.rows - 2 < 0 ? 0 : m.rows - 2);
  const int x1 = std::min(x0 + 1, m.cols - 1), y1 = std::min(y0 + 1, m.rows - 1);
  const float fx = float(x - x0), fy = float(y - y0);
  return (m(y0, x0) * (1 - fx) + m(y0, x1) * fx) * (1 - fy) +
         (m(y1, x0) * (1 - fx) + m(y1, x1) * fx) * fy;
}

// Whether (x, y) lies within the pixel centres of `m` (where SampleBilinear
// interpolates rather than extends the border).
template <typename T>
bool InsideImage(const cv::Mat_<T>& m, double x, double y) {
  return x >= 0 && y >= 0 && x <= m.cols - 1 && y <= m.rows - 1;
}

}  // namespace docunfold
