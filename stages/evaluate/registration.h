// How much of a result's loss one affine map explains: the result registered
// to the ground truth by the best single affine map, and MS-SSIM after it.
// A crop whose sides sit a little off the page's, or a page a fraction of a
// percent too short along one axis, shifts every line by a growing amount,
// and MS-SSIM counts that as heavily as a wrong local shape; this separates
// the two (docs/decisions/evaluate.md, "Loss one affine map explains").
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace docunfold::evaluate {

// One map tried: how it was found and what the result scores through it.
struct AffineCandidate {
  std::string fit;  // "ransac", "least-squares", "ransac-rest", "ransac-rest-2" or -3, "identity"
  cv::Matx23d result_from_truth;
  int samples = 0;         // flow vectors on the truth's ink the fit used
  double residual_px = 0;  // their rms distance from the map, evaluation pixels
  double ms_ssim = 0;      // of the result resampled through the map
};

struct AffineRegistration {
  // The candidate that scores best. result_from_truth: where the result
  // shows a point of the ground truth, both in evaluation-size pixels (the
  // MS-SSIM size): result = A * (x, y, 1).
  std::string fit;
  cv::Matx23d result_from_truth;
  int samples = 0;
  double residual_px = 0;
  double ms_ssim = 0;
  std::vector<AffineCandidate> candidates;  // every map tried, in the order below
};

// `flow`: HalfSizeFlow(ground_truth, result). Maps are fitted to the flow
// where the ground truth has ink (its half-size gradient is strong), since
// DeepFlow only interpolates over blank paper: by RANSAC refined on its
// inliers, by least squares over every such vector, and by RANSAC again over
// the vectors the first left out (a page folded in two moves by two maps, and
// the larger consensus is not always the better half); the identity is the
// last candidate, so the registered score is never below the plain one.
// Nothing when fewer than 50 such vectors agree on the first RANSAC map.
std::optional<AffineRegistration> RegisterAffine(const cv::Mat1b& ground_truth,
                                                 const cv::Mat1b& result, const cv::Mat2f& flow);

}  // namespace docunfold::evaluate
