// Sampling a photo for an output pixel whose footprint in the photo is
// the parallelogram spanned by the columns of a 2x2 Jacobian J (photo pixels per output pixel along
// output x and y).
//
// Magnification (footprint <= 1.25 pixels): one bicubic sample (Keys,
// a = -0.5). Minification: the footprint is an ellipse with axes
// sigma1 >= sigma2 along e1, e2; a grid of up to kMaxTaps x kMaxTaps
// bicubic samples spread over sigma1 x sigma2 averages it (a box filter,
// like an area resize, also when the footprint is long and thin as on a
// page seen at a slant), each sample taken from the Gaussian pyramid level
// whose pixel is at most half the footprint's minor width.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "common/raster.h"

namespace docunfold {

class TextureSampler {
 public:
  static constexpr int kMaxTaps = 8;

  // `image`: 8-bit, 3 channels. Builds pyramid levels down to ~8 pixels.
  explicit TextureSampler(const cv::Mat& image);

  // Colour at photo pixel (u, v) (centres at integers; clamped to the
  // image) for footprint J = [du/dx du/dy; dv/dx dv/dy]. `antialias` false
  // gives plain bicubic whatever J. Returns whether pre-filtering was used.
  bool Sample(float u, float v, const float J[4], bool antialias, float out[3]) const;

  int num_levels() const { return int(levels_.size()); }

 private:
  // Bicubic at level `level`, coordinates of level 0; adds weight * colour.
  void Bicubic(int level, float u, float v, float weight, float acc[3]) const;

  std::vector<cv::Mat> levels_;  // level k has 2^-k the size; pixel x of level
                                 // k sits at pixel 2^k x of level 0 (pyrDown)
};

// Per triangle, d(surface point)/d(output pixel): the affine map from the
// triangle in `flat` (M', `scale` output pixels per unit) onto the same
// triangle of `surface` (M, in any frame); zero for a degenerate triangle.
// Times a camera's projection Jacobian it is an output pixel's footprint.
std::vector<Eigen::Matrix<double, 3, 2>> SurfacePerOutputPixel(
    const std::vector<Eigen::Vector3d>& surface, const std::vector<Eigen::Vector2d>& flat,
    const std::vector<Triangle>& triangles, double scale);

}  // namespace docunfold
