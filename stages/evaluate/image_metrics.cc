#include "stages/evaluate/image_metrics.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/optflow.hpp>
#include <stdexcept>

namespace docunfold::evaluate {

cv::Mat1b MatlabGrey(const cv::Mat& image) {
  if (image.depth() != CV_8U) throw std::invalid_argument("MatlabGrey: 8-bit image expected");
  if (image.channels() == 1) return image.clone();
  if (image.channels() != 3 && image.channels() != 4)
    throw std::invalid_argument("MatlabGrey: 1, 3 or 4 channels expected");
  // rgb2gray's weights (the inverse of the NTSC YIQ transform's first row).
  constexpr double kR = 0.298936021293775, kG = 0.587043074451121, kB = 0.114020904255103;
  cv::Mat1b grey(image.size());
  const int channels = image.channels();
  for (int y = 0; y < image.rows; ++y) {
    const uint8_t* in = image.ptr<uint8_t>(y);
    uint8_t* out = grey.ptr<uint8_t>(y);
    for (int x = 0; x < image.cols; ++x, in += channels) {
      const double v = kB * in[0] + kG * in[1] + kR * in[2];
      out[x] = cv::saturate_cast<uint8_t>(std::lround(v));
    }
  }
  return grey;
}

cv::Size EvaluationSize(cv::Size ground_truth) {
  if (ground_truth.area() <= 0) throw std::invalid_argument("EvaluationSize: empty image");
  const double scale = std::sqrt(kEvaluationArea / ground_truth.area());
  // MATLAB's imresize(img, scale) gives ceil(scale * size); the tiny epsilon
  // keeps an exact product (scale 1, 0.5) from rounding up by float noise.
  auto side = [&](int n) { return std::max(1, int(std::ceil(scale * n - 1e-9))); };
  return {side(ground_truth.width), side(ground_truth.height)};
}

EvaluationPair PrepareEvaluationPair(const cv::Mat& ground_truth_bgr, const cv::Mat& result_bgr) {
  const cv::Size size = EvaluationSize(ground_truth_bgr.size());
  EvaluationPair pair;
  cv::resize(MatlabGrey(ground_truth_bgr), pair.ground_truth, size, 0, 0, cv::INTER_AREA);
  cv::resize(MatlabGrey(result_bgr), pair.result, size, 0, 0, cv::INTER_AREA);
  return pair;
}

double Ssim(const cv::Mat1b& a, const cv::Mat1b& b) {
  if (a.size() != b.size() || a.empty())
    throw std::invalid_argument("Ssim: images of equal, non-zero size expected");
  constexpr double kC1 = (0.01 * 255) * (0.01 * 255);
  constexpr double kC2 = (0.03 * 255) * (0.03 * 255);
  cv::Mat1d x, y;
  a.convertTo(x, CV_64F);
  b.convertTo(y, CV_64F);
  auto blur = [](const cv::Mat1d& m) {
    cv::Mat1d out;
    cv::GaussianBlur(m, out, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REPLICATE);
    return out;
  };
  const cv::Mat1d mx = blur(x), my = blur(y);
  const cv::Mat1d sxx = blur(x.mul(x)) - mx.mul(mx);
  const cv::Mat1d syy = blur(y.mul(y)) - my.mul(my);
  const cv::Mat1d sxy = blur(x.mul(y)) - mx.mul(my);
  double sum = 0;
  for (int r = 0; r < x.rows; ++r) {
    for (int c = 0; c < x.cols; ++c) {
      const double ux = mx(r, c), uy = my(r, c);
      const double num = (2 * ux * uy + kC1) * (2 * sxy(r, c) + kC2);
      const double den = (ux * ux + uy * uy + kC1) * (sxx(r, c) + syy(r, c) + kC2);
      sum += num / den;
    }
  }
  return sum / double(x.total());
}

MsSsimResult MsSsim(const cv::Mat1b& ground_truth, const cv::Mat1b& result) {
  MsSsimResult out;
  cv::Mat1b a = ground_truth, b = result;
  double weight_sum = 0;
  for (size_t s = 0; s < kMsSsimWeights.size(); ++s) {
    out.scales[s] = Ssim(a, b);
    out.value += kMsSsimWeights[s] * out.scales[s];
    weight_sum += kMsSsimWeights[s];
    if (s + 1 == kMsSsimWeights.size()) break;
    cv::Mat1b next_a, next_b;
    cv::pyrDown(a, next_a, cv::Size(), cv::BORDER_REFLECT);
    cv::pyrDown(b, next_b, cv::Size(), cv::BORDER_REFLECT);
    a = next_a;
    b = next_b;
  }
  out.value /= weight_sum;
  return out;
}

cv::Mat2f DeepFlow(const cv::Mat1b& from, const cv::Mat1b& to) {
  if (from.size() != to.size() || from.empty())
    throw std::invalid_argument("DeepFlow: images of equal, non-zero size expected");
  cv::Ptr<cv::DenseOpticalFlow> deepflow = cv::optflow::createOptFlow_DeepFlow();
  cv::Mat flow;
  deepflow->calc(from, to, flow);
  return flow;
}

FlowResult FlowStatistics(const cv::Mat2f& flow) {
  FlowResult out;
  out.size = flow.size();
  if (flow.empty()) return out;
  double length_sum = 0;
  for (int r = 0; r < flow.rows; ++r)
    for (int c = 0; c < flow.cols; ++c) length_sum += std::hypot(flow(r, c)[0], flow(r, c)[1]);
  out.ld = length_sum / double(flow.total());
  // Sample standard deviation (N - 1), as MATLAB's std().
  auto sample_std = [](double sum, double sum_sq, int n) {
    if (n < 2) return 0.0;
    const double mean = sum / n;
    return std::sqrt(std::max(0.0, (sum_sq - n * mean * mean) / (n - 1)));
  };
  double rows_std = 0;  // std of v_y along each row: rows should stay rows
  for (int r = 0; r < flow.rows; ++r) {
    double s = 0, ss = 0;
    for (int c = 0; c < flow.cols; ++c) {
      const double v = flow(r, c)[1];
      s += v;
      ss += v * v;
    }
    rows_std += sample_std(s, ss, flow.cols);
  }
  double cols_std = 0;  // std of v_x down each column
  for (int c = 0; c < flow.cols; ++c) {
    double s = 0, ss = 0;
    for (int r = 0; r < flow.rows; ++r) {
      const double v = flow(r, c)[0];
      s += v;
      ss += v * v;
    }
    cols_std += sample_std(s, ss, flow.rows);
  }
  out.li_d = 0.5 * (rows_std / flow.rows + cols_std / flow.cols);
  return out;
}

cv::Mat1b BlurredHalf(const cv::Mat1b& image) {
  const cv::Size half((image.cols + 1) / 2, (image.rows + 1) / 2);
  cv::Mat1b blurred, small;
  cv::GaussianBlur(image, blurred, cv::Size(7, 7), 1.0, 1.0, cv::BORDER_REPLICATE);
  cv::resize(blurred, small, half, 0, 0, cv::INTER_AREA);
  return small;
}

cv::Mat2f HalfSizeFlow(const cv::Mat1b& ground_truth, const cv::Mat1b& result) {
  return DeepFlow(BlurredHalf(ground_truth), BlurredHalf(result));
}

FlowResult DenseFlowMetrics(const cv::Mat1b& ground_truth, const cv::Mat1b& result) {
  return FlowStatistics(HalfSizeFlow(ground_truth, result));
}

}  // namespace docunfold::evaluate
