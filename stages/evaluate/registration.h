// How much of a result's loss one affine map explains: the result registered
// to the ground truth by the best single affine map, and MS-SSIM after it.
// A crop whose sides sit a little off the page's, or a page a fraction of a
// percent too short along one axis, shifts every line by a growing amount,
// and MS-SSIM counts that as heavily as a wrong local shape; this separates
// the two (docs/decisions/evaluate.md, "Loss one affine map explains").
#pragma once

#include <opencv2/core.hpp>
#include <optional>

namespace docunfold::evaluate {

struct AffineRegistration {
  // Where the result shows a point of the ground truth, both in evaluation-
  // size pixels (the MS-SSIM size): result = A * (x, y, 1).
  cv::Matx23d result_from_truth;
  int samples = 0;         // flow vectors on the truth's ink that the fit kept
  double residual_px = 0;  // their rms distance from the map, evaluation pixels
  double ms_ssim = 0;      // of the result resampled through the map
};

// `flow`: HalfSizeFlow(ground_truth, result). The map is fitted (RANSAC,
// then refined on the inliers) to the flow where the ground truth has ink
// (its half-size gradient is strong), since DeepFlow only interpolates over
// blank paper. Nothing when fewer than 50 such vectors agree.
std::optional<AffineRegistration> RegisterAffine(const cv::Mat1b& ground_truth,
                                                 const cv::Mat1b& result, const cv::Mat2f& flow);

}  // namespace docunfold::evaluate
