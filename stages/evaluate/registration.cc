#include "stages/evaluate/registration.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "stages/evaluate/image_metrics.h"

namespace docunfold::evaluate {
namespace {

// Flow vectors are taken on a grid this many half-size pixels apart, where the
// blurred truth's gradient is at least kMinGradient grey levels per pixel.
constexpr int kStride = 2;
constexpr double kMinGradient = 12;
constexpr double kRansacPx = 1.0;  // half-size pixels
constexpr int kMinSamples = 50;
constexpr int kMaxRest = 3;  // RANSAC fits over what earlier fits left out

}  // namespace

std::optional<AffineRegistration> RegisterAffine(const cv::Mat1b& ground_truth,
                                                 const cv::Mat1b& result, const cv::Mat2f& flow) {
  const cv::Mat1b half = BlurredHalf(ground_truth);
  if (half.size() != flow.size()) return std::nullopt;
  cv::Mat1f gx, gy;
  cv::Sobel(half, gx, CV_32F, 1, 0, 3, 1.0 / 8);
  cv::Sobel(half, gy, CV_32F, 0, 1, 3, 1.0 / 8);
  std::vector<cv::Point2f> from, to;
  for (int r = 0; r < half.rows; r += kStride)
    for (int c = 0; c < half.cols; c += kStride) {
      if (std::hypot(gx(r, c), gy(r, c)) < kMinGradient) continue;
      const cv::Vec2f f = flow(r, c);
      if (!std::isfinite(f[0]) || !std::isfinite(f[1])) continue;
      from.emplace_back(float(c), float(r));
      to.emplace_back(float(c) + f[0], float(r) + f[1]);
    }
  if (int(from.size()) < kMinSamples) return std::nullopt;
  std::vector<uchar> inlier;
  const cv::Mat ransac_map = cv::estimateAffine2D(from, to, inlier, cv::RANSAC, kRansacPx);
  if (ransac_map.empty()) return std::nullopt;
  if (cv::countNonZero(inlier) < kMinSamples) return std::nullopt;

  // Half-size pixels to evaluation-size pixels, per axis, pixel centres
  // matched as INTER_AREA matches them: full = s * half + (s - 1) / 2.
  // A_full = H A_half H^-1.
  const double sx = double(ground_truth.cols) / half.cols;
  const double sy = double(ground_truth.rows) / half.rows;
  const cv::Matx33d h(sx, 0, 0.5 * (sx - 1), 0, sy, 0.5 * (sy - 1), 0, 0, 1);
  auto candidate = [&](const std::string& fit, const cv::Matx23d& a,
                       const std::vector<uchar>& used) {
    AffineCandidate out;
    out.fit = fit;
    double squares = 0;
    for (size_t i = 0; i < from.size(); ++i) {
      if (!used[i]) continue;
      const cv::Point2d p = from[i];
      const cv::Point2d q(a(0, 0) * p.x + a(0, 1) * p.y + a(0, 2),
                          a(1, 0) * p.x + a(1, 1) * p.y + a(1, 2));
      const cv::Point2d e = q - cv::Point2d(to[i]);
      squares += e.dot(e);
      ++out.samples;
    }
    const cv::Matx33d a3(a(0, 0), a(0, 1), a(0, 2), a(1, 0), a(1, 1), a(1, 2), 0, 0, 1);
    const cv::Matx33d full = h * a3 * h.inv();
    out.residual_px = std::sqrt(squares / std::max(1, out.samples)) * 0.5 * (sx + sy);
    out.result_from_truth = full.get_minor<2, 3>(0, 0);
    cv::Mat1b registered;
    cv::warpAffine(result, registered, cv::Mat(out.result_from_truth), ground_truth.size(),
                   cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
    out.ms_ssim = MsSsim(ground_truth, registered).value;
    return out;
  };
  const std::vector<uchar> all(from.size(), 1);
  AffineRegistration reg;
  reg.candidates.push_back(candidate("ransac", cv::Matx23d(ransac_map), inlier));
  // Least squares: to ≈ A (from, 1), both rows of A at once.
  cv::Mat1d design(int(from.size()), 3), target(int(from.size()), 2);
  for (int i = 0; i < int(from.size()); ++i) {
    design(i, 0) = from[size_t(i)].x;
    design(i, 1) = from[size_t(i)].y;
    design(i, 2) = 1;
    target(i, 0) = to[size_t(i)].x;
    target(i, 1) = to[size_t(i)].y;
  }
  cv::Mat1d solution;
  if (cv::solve(design, target, solution, cv::DECOMP_SVD)) {
    const cv::Matx23d a(solution(0, 0), solution(1, 0), solution(2, 0), solution(0, 1),
                        solution(1, 1), solution(2, 1));
    reg.candidates.push_back(candidate("least-squares", a, all));
  }
  // The vectors no fit so far took: the page's other side across a fold, or
  // the page where a consensus was a patch of it. Peeled up to kMaxRest times,
  // since which part a fit locks onto first changes with small changes of
  // the result.
  std::vector<uchar> taken = inlier;
  for (int round = 1; round <= kMaxRest; ++round) {
    std::vector<cv::Point2f> rest_from, rest_to;
    std::vector<size_t> rest_index;
    for (size_t i = 0; i < from.size(); ++i)
      if (!taken[i]) {
        rest_from.push_back(from[i]);
        rest_to.push_back(to[i]);
        rest_index.push_back(i);
      }
    if (int(rest_from.size()) < kMinSamples) break;
    std::vector<uchar> rest_inlier;
    const cv::Mat rest_map =
        cv::estimateAffine2D(rest_from, rest_to, rest_inlier, cv::RANSAC, kRansacPx);
    if (rest_map.empty() || cv::countNonZero(rest_inlier) < kMinSamples) break;
    std::vector<uchar> used(from.size(), 0);
    for (size_t k = 0; k < rest_index.size(); ++k) used[rest_index[k]] = rest_inlier[k];
    for (size_t i = 0; i < from.size(); ++i) taken[i] |= used[i];
    reg.candidates.push_back(
        candidate(round == 1 ? "ransac-rest" : "ransac-rest-" + std::to_string(round),
                  cv::Matx23d(rest_map), used));
  }
  reg.candidates.push_back(candidate("identity", cv::Matx23d(1, 0, 0, 0, 1, 0), all));
  const AffineCandidate* best = &reg.candidates.front();
  for (const AffineCandidate& c : reg.candidates)
    if (c.ms_ssim > best->ms_ssim) best = &c;
  reg.fit = best->fit;
  reg.result_from_truth = best->result_from_truth;
  reg.samples = best->samples;
  reg.residual_px = best->residual_px;
  reg.ms_ssim = best->ms_ssim;
  return reg;
}

}  // namespace docunfold::evaluate
