#include "common/shading.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/statistics.h"

namespace docunfold {
namespace {

cv::Mat Disc(int radius) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
}

// Mean of the three channels.
cv::Mat1f Grey(const cv::Mat3f& bgr) {
  cv::Mat1f grey;
  cv::transform(bgr, grey, cv::Matx13f(1.f / 3, 1.f / 3, 1.f / 3));
  return grey;
}

// The brightest grey within `radius` pixels, smoothed: what the paper there
// would show if it were all paper. Found on a copy a quarter of the radius
// per pixel (the envelope is coarse), with a square (separable, fast).
cv::Mat1f Envelope(const cv::Mat1f& grey, int radius) {
  const double shrink = std::min(1.0, 4.0 / std::max(radius, 1));
  cv::Mat1f small;
  cv::resize(grey, small, cv::Size(), shrink, shrink, cv::INTER_AREA);
  const int r = std::max(1, int(std::lround(radius * shrink)));
  cv::dilate(small, small,
             cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1)));
  cv::GaussianBlur(small, small, cv::Size(), std::max(0.5, r / 2.0));
  cv::Mat1f envelope;
  cv::resize(small, envelope, grey.size(), 0, 0, cv::INTER_LINEAR);
  return envelope;
}

// Gaussian blur by `sigma`; wide ones on a copy shrunk to about 4 pixels per
// sigma (the result is smooth at that scale anyway).
template <class Mat>
Mat Blur(const Mat& m, double sigma) {
  Mat out;
  if (sigma <= 8) {
    cv::GaussianBlur(m, out, cv::Size(), sigma);
    return out;
  }
  const double shrink = 4 / sigma;
  Mat small;
  cv::resize(m, small, cv::Size(), shrink, shrink, cv::INTER_AREA);
  cv::GaussianBlur(small, small, cv::Size(), 4.0);
  cv::resize(small, out, m.size(), 0, 0, cv::INTER_LINEAR);
  return out;
}

}  // namespace

ShadingRemoval RemoveShading(const cv::Mat& input, const ShadingOptions& o) {
  ShadingRemoval out;
  out.image = input.clone();
  if (input.empty()) return out;
  CV_Assert(input.depth() == CV_8U && (input.channels() == 1 || input.channels() == 3));
  cv::Mat bgr = input;
  if (input.channels() == 1) cv::cvtColor(input, bgr, cv::COLOR_GRAY2BGR);

  // Working copy.
  const int long_side = std::max(bgr.cols, bgr.rows);
  const double scale = std::min(1.0, double(std::max(o.work_size, 16)) / long_side);
  cv::Mat small_bytes;
  if (scale < 1)
    cv::resize(bgr, small_bytes, cv::Size(), scale, scale, cv::INTER_AREA);
  else
    small_bytes = bgr;
  const int work_long = std::max(small_bytes.cols, small_bytes.rows);

  // Print lifted out: a closing wider than its strokes (on bytes: fast).
  const int stroke = std::max(2, int(std::lround(o.stroke_fraction * work_long)));
  cv::Mat closed_bytes;
  cv::morphologyEx(small_bytes, closed_bytes, cv::MORPH_CLOSE, Disc(stroke));
  cv::Mat3f closed;
  closed_bytes.convertTo(closed, CV_32FC3);
  const cv::Mat1f grey = Grey(closed);

  // Paper: bright for its neighbourhood and of the paper's chromaticity.
  const cv::Mat1f envelope =
      Envelope(grey, std::max(3, int(std::lround(o.envelope_fraction * work_long))));
  cv::Mat3f chroma(closed.size());
  for (int y = 0; y < closed.rows; ++y)
    for (int x = 0; x < closed.cols; ++x) {
      const cv::Vec3f c = closed(y, x);
      chroma(y, x) = c / std::max(c[0] + c[1] + c[2], 1.f);
    }
  // Quantiles from every other pixel in each direction: plenty, and faster.
  std::vector<double> greys;
  for (int y = 0; y < grey.rows; y += 2)
    for (int x = 0; x < grey.cols; x += 2) greys.push_back(grey(y, x));
  const double bright = Quantile(greys, 0.7);
  std::array<std::vector<double>, 3> bright_chroma;
  for (int y = 0; y < closed.rows; y += 2)
    for (int x = 0; x < closed.cols; x += 2)
      if (grey(y, x) >= bright)
        for (int c = 0; c < 3; ++c) bright_chroma[c].push_back(chroma(y, x)[c]);
  cv::Vec3f paper_chroma;
  for (int c = 0; c < 3; ++c) paper_chroma[c] = float(Median(bright_chroma[c]));
  cv::Mat1f paper(closed.size(), 0.f);
  int paper_pixels = 0;
  for (int y = 0; y < closed.rows; ++y)
    for (int x = 0; x < closed.cols; ++x)
      if (cv::norm(chroma(y, x) - paper_chroma) < o.max_chroma_distance &&
          grey(y, x) >= o.min_paper_ratio * envelope(y, x) && grey(y, x) > 0) {
        paper(y, x) = 1;
        ++paper_pixels;
      }
  out.paper_fraction = double(paper_pixels) / double(closed.total());
  if (paper_pixels == 0) return out;

  // The paper's brightness everywhere: normalised convolution of the closed
  // image over the paper, widened until it reaches every pixel.
  cv::Mat3f weighted;
  {
    std::vector<cv::Mat1f> channels;
    cv::split(closed, channels);
    for (cv::Mat1f& ch : channels) ch = ch.mul(paper);
    cv::merge(channels, weighted);
  }
  cv::Mat3f light(closed.size(), cv::Vec3f(0, 0, 0));
  cv::Mat1b unset(closed.size(), 255);
  for (double sigma = std::max(1.0, stroke / 2.0);; sigma *= 2) {
    const cv::Mat3f num = Blur(weighted, sigma);
    const cv::Mat1f den = Blur(paper, sigma);
    const bool last = sigma > work_long;
    for (int y = 0; y < closed.rows; ++y)
      for (int x = 0; x < closed.cols; ++x)
        if (unset(y, x) && (den(y, x) > 0.2f || (last && den(y, x) > 0))) {
          light(y, x) = num(y, x) / den(y, x);
          unset(y, x) = 0;
        }
    if (last || cv::countNonZero(unset) == 0) break;
  }
  // Anything still unset (no paper anywhere near, which `last` rules out
  // unless den underflows) keeps its own brightness.
  closed.copyTo(light, unset);

  // Paper maps to its well-lit colour.
  std::array<std::vector<double>, 3> paper_light;
  for (int y = 0; y < light.rows; y += 2)
    for (int x = 0; x < light.cols; x += 2)
      if (paper(y, x) > 0)
        for (int c = 0; c < 3; ++c) paper_light[c].push_back(light(y, x)[c]);
  for (int c = 0; c < 3; ++c) out.paper_white[c] = Quantile(paper_light[c], o.white_quantile);

  cv::Mat3f full_light;
  cv::resize(light, full_light, bgr.size(), 0, 0, cv::INTER_LINEAR);
  cv::max(full_light, 1.0, full_light);
  cv::Mat3f image;
  bgr.convertTo(image, CV_32FC3);
  cv::divide(image, full_light, image);
  cv::multiply(image, cv::Scalar(out.paper_white[0], out.paper_white[1], out.paper_white[2]),
               image);
  cv::Mat3b result;
  image.convertTo(result, CV_8UC3);
  if (input.channels() == 1)
    cv::cvtColor(result, out.image, cv::COLOR_BGR2GRAY);
  else
    out.image = result;
  return out;
}

}  // namespace docunfold
