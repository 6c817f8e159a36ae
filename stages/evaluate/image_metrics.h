// Image metrics of the DocUNet benchmark (Ma et al., CVPR 2018) as its MATLAB
// evaluation code computes them, so our figures sit beside published ones:
// MS-SSIM, and the flow-based local distortion LD with its line variant Li-D.
#pragma once

#include <array>
#include <opencv2/core.hpp>

namespace docunfold::evaluate {

// Pixel area to which the ground truth is resized before comparison
// (DocUNet's "tarea").
constexpr double kEvaluationArea = 598400;

// Grey levels with MATLAB's rgb2gray weights, rounded to 8 bits as
// rgb2gray does for uint8 input. Accepts 8-bit BGR, BGRA or grey images.
cv::Mat1b MatlabGrey(const cv::Mat& image);

// Size of the ground truth resized to an area of kEvaluationArea pixels
// keeping its aspect: MATLAB imresize's ceil(scale * size).
cv::Size EvaluationSize(cv::Size ground_truth);

// Both images in grey at the evaluation size (INTER_AREA, the closest OpenCV
// match to MATLAB's antialiased bicubic imresize).
struct EvaluationPair {
  cv::Mat1b ground_truth;
  cv::Mat1b result;
};
EvaluationPair PrepareEvaluationPair(const cv::Mat& ground_truth_bgr, const cv::Mat& result_bgr);

// Mean SSIM of two equally sized grey images: 11x11 Gaussian window with
// sigma 1.5, replicated borders, C1 = (0.01*255)^2, C2 = (0.03*255)^2, mean
// over all pixels (MATLAB's ssim()).
double Ssim(const cv::Mat1b& a, const cv::Mat1b& b);

// DocUNet MS-SSIM weights, finest scale first.
constexpr std::array<double, 5> kMsSsimWeights = {0.0448, 0.2856, 0.3001, 0.2363, 0.1333};

struct MsSsimResult {
  double value = 0;                // weighted sum of the per-scale SSIM
  std::array<double, 5> scales{};  // full SSIM at each scale, finest first
};
// DocUNet's MS-SSIM: full SSIM at five scales, each the previous one reduced
// 2x (MATLAB impyramid 'reduce' = pyrDown with reflected borders, rounded to
// 8 bits), combined as the weighted SUM of kMsSsimWeights. Unlike the
// product form of Wang et al., every scale contributes luminance too; this
// is what reproduces the published reference values. The published weights
// sum to 1.0001; we divide by that sum so that identical images score
// exactly 1 (a change of at most 1e-4 against DocUNet's MATLAB code).
MsSsimResult MsSsim(const cv::Mat1b& ground_truth, const cv::Mat1b& result);

struct FlowResult {
  double ld = 0;    // mean flow length, pixels of the flow resolution
  double li_d = 0;  // 0.5 * (mean over rows of std(v_y) + mean over columns of std(v_x))
  cv::Size size;    // flow resolution (half the evaluation size)
};
// Dense flow from ground truth to result with DeepFlow (opencv_contrib
// optflow), a stand-in for the SIFT flow of the literature. The inputs are
// the evaluation-size grey images; like DocUNet's code they are blurred
// (7x7 Gaussian, sigma 1, replicated borders) and halved before the flow.
FlowResult DenseFlowMetrics(const cv::Mat1b& ground_truth, const cv::Mat1b& result);

// The steps of DenseFlowMetrics: an evaluation-size image blurred and
// halved, and DeepFlow from the ground truth's to the result's.
cv::Mat1b BlurredHalf(const cv::Mat1b& image);
cv::Mat2f HalfSizeFlow(const cv::Mat1b& ground_truth, const cv::Mat1b& result);

// LD and Li-D of a given flow field (CV_32FC2, (v_x, v_y) per pixel).
FlowResult FlowStatistics(const cv::Mat2f& flow);

// DeepFlow between two equally sized grey images, without the blur and
// halving of DenseFlowMetrics: I0(x) ~ I1(x + flow(x)).
cv::Mat2f DeepFlow(const cv::Mat1b& from, const cv::Mat1b& to);

}  // namespace docunfold::evaluate
