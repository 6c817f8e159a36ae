#include "common/texture_sampler.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace docunfold {
namespace {

// Keys' cubic convolution kernel with a = -0.5 (Catmull-Rom): interpolating,
// third-order accurate, less ringing than OpenCV's a = -0.75.
inline void CubicWeights(float t, float w[4]) {
  const float t2 = t * t, t3 = t2 * t;
  w[0] = -0.5f * t3 + t2 - 0.5f * t;
  w[1] = 1.5f * t3 - 2.5f * t2 + 1.0f;
  w[2] = -1.5f * t3 + 2.0f * t2 + 0.5f * t;
  w[3] = 0.5f * t3 - 0.5f * t2;
}

}  // namespace

TextureSampler::TextureSampler(const cv::Mat& image) {
  CV_Assert(image.type() == CV_8UC3);
  levels_.push_back(image);
  while (levels_.size() < 14 && std::min(levels_.back().cols, levels_.back().rows) > 16) {
    cv::Mat next;
    cv::pyrDown(levels_.back(), next);
    levels_.push_back(next);
  }
}

void TextureSampler::Bicubic(int level, float u, float v, float weight, float acc[3]) const {
  const cv::Mat& img = levels_[level];
  const float scale = 1.0f / float(1 << level);
  const float x = u * scale, y = v * scale;
  const float fx0 = std::floor(x), fy0 = std::floor(y);
  const int ix = int(fx0), iy = int(fy0);
  float wx[4], wy[4];
  CubicWeights(x - fx0, wx);
  CubicWeights(y - fy0, wy);
  int cols[4];
  for (int k = 0; k < 4; ++k) cols[k] = 3 * std::clamp(ix - 1 + k, 0, img.cols - 1);
  float sum[3] = {0, 0, 0};
  for (int j = 0; j < 4; ++j) {
    const uchar* row = img.ptr<uchar>(std::clamp(iy - 1 + j, 0, img.rows - 1));
    float r[3] = {0, 0, 0};
    for (int k = 0; k < 4; ++k) {
      const uchar* p = row + cols[k];
      r[0] += wx[k] * p[0];
      r[1] += wx[k] * p[1];
      r[2] += wx[k] * p[2];
    }
    sum[0] += wy[j] * r[0];
    sum[1] += wy[j] * r[1];
    sum[2] += wy[j] * r[2];
  }
  acc[0] += weight * sum[0];
  acc[1] += weight * sum[1];
  acc[2] += weight * sum[2];
}

bool TextureSampler::Sample(float u, float v, const float J[4], bool antialias,
                            float out[3]) const {
  out[0] = out[1] = out[2] = 0;
  if (!antialias) {
    Bicubic(0, u, v, 1, out);
    return false;
  }
  // Footprint ellipse: eigen-decomposition of J J^T = [a b; b c].
  const float a = J[0] * J[0] + J[1] * J[1];
  const float b = J[0] * J[2] + J[1] * J[3];
  const float c = J[2] * J[2] + J[3] * J[3];
  const float mean = 0.5f * (a + c);
  const float dev = std::sqrt(0.25f * (a - c) * (a - c) + b * b);
  const float sigma1 = std::sqrt(mean + dev);
  const float sigma2 = std::sqrt(std::max(mean - dev, 0.0f));
  if (!(sigma1 > 1.0f)) {  // magnifying (or a NaN Jacobian)
    Bicubic(0, u, v, 1, out);
    return false;
  }
  // Major axis of the footprint in the photo.
  float ex = 1, ey = 0;
  {
    const float l1 = mean + dev;
    const float p0x = b, p0y = l1 - a, p1x = l1 - c, p1y = b;
    const float n0 = p0x * p0x + p0y * p0y, n1 = p1x * p1x + p1y * p1y;
    if (std::max(n0, n1) > 1e-20f) {
      const float inv = 1.0f / std::sqrt(std::max(n0, n1));
      ex = (n0 > n1 ? p0x : p1x) * inv;
      ey = (n0 > n1 ? p0y : p1y) * inv;
    } else if (c > a) {
      ex = 0;
      ey = 1;
    }
  }
  // A grid of taps covers the footprint (box filter of widths sigma1 along
  // e1, sigma2 along e2), each tap a bicubic sample of the pyramid level
  // whose pixel p is at most half the minor width. A Gaussian pyramid level
  // blurs with a standard deviation of about 0.58 p, no more than the box's
  // 0.29 sigma2, so the result is as sharp as an area average (and far
  // sharper than mipmapping by the footprint, which blurs twice as much).
  // Footprints up to 1.25 pixels wide need no tap of their own.
  const float minor = std::max(sigma2, 1.0f);
  int level = std::max(0, int(std::floor(std::log2(minor))) - 1);
  if (sigma1 > kMaxTaps * float(1 << level))  // long thin footprint: coarser
    level = int(std::ceil(std::log2(sigma1 / kMaxTaps)));
  level = std::min(level, num_levels() - 1);
  const float pixel = float(1 << level);
  auto taps_for = [&](float width) {
    return width > 1.25f * pixel ? std::min(kMaxTaps, int(std::ceil(width / pixel))) : 1;
  };
  const int n1 = taps_for(sigma1), n2 = taps_for(sigma2);
  if (n1 == 1 && n2 == 1 && level == 0) {
    Bicubic(0, u, v, 1, out);
    return false;
  }
  const float w = 1.0f / float(n1 * n2);
  for (int i = 0; i < n1; ++i) {
    const float t1 = ((float(i) + 0.5f) / float(n1) - 0.5f) * sigma1;
    for (int j = 0; j < n2; ++j) {
      const float t2 = ((float(j) + 0.5f) / float(n2) - 0.5f) * sigma2;
      Bicubic(level, u + t1 * ex - t2 * ey, v + t1 * ey + t2 * ex, w, out);
    }
  }
  return true;
}

std::vector<Eigen::Matrix<double, 3, 2>> SurfacePerOutputPixel(
    const std::vector<Eigen::Vector3d>& surface, const std::vector<Eigen::Vector2d>& flat,
    const std::vector<Triangle>& triangles, double scale) {
  std::vector<Eigen::Matrix<double, 3, 2>> out(triangles.size());
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    Eigen::Matrix2d Q;
    Q << flat[t[1]] - flat[t[0]], flat[t[2]] - flat[t[0]];
    Eigen::Matrix<double, 3, 2> P;
    P << surface[t[1]] - surface[t[0]], surface[t[2]] - surface[t[0]];
    out[f] = std::abs(Q.determinant()) > 0 ? Eigen::Matrix<double, 3, 2>(P * Q.inverse() / scale)
                                           : Eigen::Matrix<double, 3, 2>::Zero();
  }
  return out;
}

}  // namespace docunfold
