// Levelling, registration and sharpness of the photos' renderings for texture fusion
// (texture_fusion_internal.h).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "common/statistics.h"
#include "common/texture_fusion_internal.h"

namespace docunfold::fusion_internal {
namespace {

// Normalized convolution: `values` (any channels) weighted by `weight`,
// blurred by sigma; where the weights around sum to less than a tenth of
// their peak, the same at `wide_sigma` takes over, and past that
// `fallback`.
cv::Mat SmoothFill(const cv::Mat& values, const cv::Mat1f& weight, double sigma, double wide_sigma,
                   const cv::Scalar& fallback) {
  const int channels = values.channels();
  std::vector<cv::Mat> planes;
  cv::split(values, planes);
  cv::Mat1f w_near, w_far;
  cv::GaussianBlur(weight, w_near, cv::Size(0, 0), sigma);
  cv::GaussianBlur(weight, w_far, cv::Size(0, 0), wide_sigma);
  double peak = 0;
  cv::minMaxLoc(w_near, nullptr, &peak);
  const float floor_near = float(0.1 * peak) + 1e-12f;
  double peak_far = 0;
  cv::minMaxLoc(w_far, nullptr, &peak_far);
  const float floor_far = float(0.02 * peak_far) + 1e-12f;
  std::vector<cv::Mat> out(channels);
  for (int c = 0; c < channels; ++c) {
    cv::Mat1f v = planes[c], vw = v.mul(weight), near, far;
    cv::GaussianBlur(vw, near, cv::Size(0, 0), sigma);
    cv::GaussianBlur(vw, far, cv::Size(0, 0), wide_sigma);
    cv::Mat1f o(v.size());
    for (int y = 0; y < o.rows; ++y)
      for (int x = 0; x < o.cols; ++x) {
        const float a = w_near(y, x), b = w_far(y, x);
        const float fn = near(y, x) / std::max(a, 1e-12f), ff = far(y, x) / std::max(b, 1e-12f);
        const float t = std::min(1.0f, a / floor_near);  // 1: near enough data
        const float g = b > floor_far ? ff : float(fallback[c]);
        o(y, x) = t * fn + (1 - t) * g;
      }
    out[c] = o;
  }
  cv::Mat merged;
  cv::merge(out, merged);
  return merged;
}

// The gain field (per channel, output size) that levels `view` to `target`
// on their overlap: block medians of target / view, each replaced by the
// median of the blocks around it (a glare spot of a block or two is
// outvoted), then smoothed and carried over the whole output.
cv::Mat3f GainField(const cv::Mat3f& target, const cv::Mat1b& target_valid,
                    const ViewRendering& view, int block, cv::Vec3d* mean_gain) {
  const int W = target.cols, H = target.rows;
  block = std::clamp(block, 4, std::max(W, H));
  const int gw = (W + block - 1) / block, gh = (H + block - 1) / block;
  cv::Mat3f grid(gh, gw, cv::Vec3f(1, 1, 1));
  cv::Mat1b has(gh, gw, uchar(0));
  std::vector<double> all[3];
  for (int by = 0; by < gh; ++by)
    for (int bx = 0; bx < gw; ++bx) {
      std::vector<double> ratios[3];
      for (int y = by * block; y < std::min(H, (by + 1) * block); ++y)
        for (int x = bx * block; x < std::min(W, (bx + 1) * block); ++x) {
          if (!target_valid(y, x) || !(view.resolution(y, x) > 0)) continue;
          const cv::Vec3b v = view.colour(y, x);
          if (v[0] + v[1] + v[2] < 30) continue;  // print: its ratio is noise
          for (int c = 0; c < 3; ++c)
            ratios[c].push_back(target(y, x)[c] / std::max(1.0, double(v[c])));
        }
      if (int(ratios[0].size()) < block * block / 4) continue;
      for (int c = 0; c < 3; ++c) {
        grid(by, bx)[c] = float(Median(ratios[c]));
        all[c].push_back(grid(by, bx)[c]);
      }
      has(by, bx) = 1;
    }
  cv::Scalar fallback(1, 1, 1);
  for (int c = 0; c < 3; ++c)
    if (!all[c].empty()) fallback[c] = Median(all[c]);
  // Each block's gain: the median of the measured blocks in its 5x5.
  cv::Mat3f robust = grid.clone();
  for (int by = 0; by < gh; ++by)
    for (int bx = 0; bx < gw; ++bx) {
      if (!has(by, bx)) continue;
      std::vector<double> around[3];
      for (int j = std::max(0, by - 2); j <= std::min(gh - 1, by + 2); ++j)
        for (int i = std::max(0, bx - 2); i <= std::min(gw - 1, bx + 2); ++i)
          if (has(j, i))
            for (int c = 0; c < 3; ++c) around[c].push_back(grid(j, i)[c]);
      for (int c = 0; c < 3; ++c) robust(by, bx)[c] = float(Median(around[c]));
    }
  cv::Mat1f weight;
  has.convertTo(weight, CV_32F);
  cv::Mat smooth = SmoothFill(robust, weight, 1.0, 4.0, fallback);
  cv::Mat3f field;
  cv::resize(smooth, field, cv::Size(gw * block, gh * block), 0, 0, cv::INTER_LINEAR);
  field = field(cv::Rect(0, 0, W, H)).clone();
  cv::min(field, 3.0, field);
  cv::max(field, 1.0 / 3, field);
  cv::Scalar m = cv::mean(field, view.Valid());
  *mean_gain = cv::Vec3d(m[0], m[1], m[2]);
  return field;
}

void ApplyGain(const cv::Mat3f& gain, ViewRendering* view) {
  cv::Mat3f c;
  view->colour.convertTo(c, CV_32F);
  c = c.mul(gain);
  c.convertTo(view->colour, CV_8U);
}

// Flow (output pixels) that moves `view` onto `target` where both show the
// surface, carried smoothly over the rest of the output; `p95` its 95th
// percentile on the overlap.
cv::Mat2f FlowOntoTarget(const cv::Mat3f& target, const cv::Mat1b& target_valid,
                         const ViewRendering& view, double max_flow, double* p95) {
  const int W = target.cols, H = target.rows;
  cv::Mat3b t8, v8 = view.colour.clone();
  target.convertTo(t8, CV_8U);
  const cv::Mat1b vvalid = view.Valid();
  // Each filled with the other where it shows nothing: no edge there to lock onto.
  t8.copyTo(v8, ~vvalid);
  view.colour.copyTo(t8, ~target_valid & vvalid);
  cv::Mat tg, vg;
  cv::cvtColor(t8, tg, cv::COLOR_BGR2GRAY);
  cv::cvtColor(v8, vg, cv::COLOR_BGR2GRAY);
  // At half size: misregistration is smooth, and the flow costs a quarter.
  cv::Mat ts, vs;
  cv::resize(tg, ts, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  cv::resize(vg, vs, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
  cv::Mat flow_small;
  dis->calc(ts, vs, flow_small);
  cv::Mat2f flow;
  cv::resize(flow_small, flow, cv::Size(W, H), 0, 0, cv::INTER_LINEAR);
  flow *= 2.0;
  // Trusted where both show the surface, away from their edges, on detail
  // (blank paper gives the flow nothing to hold on to).
  cv::Mat1b both = target_valid & vvalid;
  cv::erode(both, both, cv::Mat(), cv::Point(-1, -1), 4);
  cv::Mat1f gx, gy, energy;
  cv::Sobel(tg, gx, CV_32F, 1, 0);
  cv::Sobel(tg, gy, CV_32F, 0, 1);
  energy = gx.mul(gx) + gy.mul(gy);
  cv::GaussianBlur(energy, energy, cv::Size(0, 0), 4);
  cv::Mat1f weight(H, W, 0.0f);
  energy.copyTo(weight, both);
  const double limit = max_flow * std::hypot(W, H);
  std::vector<double> magnitudes;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      if (!both(y, x)) continue;
      const cv::Vec2f f = flow(y, x);
      const double m = std::hypot(f[0], f[1]);
      if (m > limit) weight(y, x) = 0;  // the photos disagree on more than a shift
      if ((x + y) % 4 == 0) magnitudes.push_back(m);
    }
  *p95 = magnitudes.empty() ? 0 : NthSmallest(magnitudes, size_t(0.95 * (magnitudes.size() - 1)));
  // Smoothed and carried on at most 256 pixels a side: the blur that carries
  // it across a tenth of the page would cost seconds at full size.
  const double f = std::min(1.0, 256.0 / std::max(W, H));
  const cv::Size small(std::max(1, int(std::lround(W * f))), std::max(1, int(std::lround(H * f))));
  std::vector<cv::Mat1f> planes;
  cv::split(flow, planes);
  cv::Mat1f ws, fx, fy;
  cv::resize(weight, ws, small, 0, 0, cv::INTER_AREA);
  cv::resize(planes[0].mul(weight), fx, small, 0, 0, cv::INTER_AREA);
  cv::resize(planes[1].mul(weight), fy, small, 0, 0, cv::INTER_AREA);
  cv::Mat2f mean_flow;
  cv::merge(std::vector<cv::Mat>{fx / (ws + 1e-12f), fy / (ws + 1e-12f)}, mean_flow);
  const double diag = std::hypot(small.width, small.height);
  const cv::Mat smooth = SmoothFill(mean_flow, ws, 0.01 * diag, 0.1 * diag, cv::Scalar(0, 0));
  cv::Mat2f full;
  cv::resize(smooth, full, cv::Size(W, H), 0, 0, cv::INTER_LINEAR);
  return full;  // output pixels at any scale
}

ViewRendering Remap(const ViewRendering& v, const cv::Mat2f& flow) {
  cv::Mat2f map(flow.size());
  for (int y = 0; y < map.rows; ++y)
    for (int x = 0; x < map.cols; ++x) map(y, x) = flow(y, x) + cv::Vec2f(float(x), float(y));
  ViewRendering out;
  cv::remap(v.colour, out.colour, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  cv::remap(v.resolution, out.resolution, map, cv::noArray(), cv::INTER_NEAREST,
            cv::BORDER_CONSTANT, 0);
  cv::remap(v.minified, out.minified, map, cv::noArray(), cv::INTER_NEAREST, cv::BORDER_CONSTANT,
            0);
  // Bilinear colour at the rendering's edge mixes in the empty black.
  cv::Mat1b inside = out.resolution > 0;
  cv::erode(inside, inside, cv::Mat());
  out.resolution.setTo(0, ~inside);
  return out;
}

}  // namespace

void LevelAndRegister(const FusionOptions& o, std::vector<ViewRendering>* renderings,
                      std::vector<FusionViewReport>* reports) {
  std::vector<ViewRendering>& r = *renderings;
  const int n = int(r.size());
  cv::Mat3f target;
  r[0].colour.convertTo(target, CV_32F);
  cv::Mat1b target_valid = r[0].Valid();
  std::vector<char> done(n, 0);
  done[0] = 1;
  for (int step = 1; step < n; ++step) {
    int next = -1, most = -1;
    for (int v = 1; v < n; ++v) {
      if (done[v]) continue;
      const int overlap = cv::countNonZero(target_valid & r[v].Valid());
      if (overlap > most) most = overlap, next = v;
    }
    done[next] = 1;
    ViewRendering& view = r[next];
    FusionViewReport& report = (*reports)[next];
    if (cv::countNonZero(view.Valid()) == 0) continue;
    ApplyGain(GainField(target, target_valid, view, o.gain_block_px, &report.gain), &view);
    if (o.register_views && most >= 1000)
      view = Remap(view, FlowOntoTarget(target, target_valid, view, o.max_flow, &report.flow_p95));
    const cv::Mat1b add = view.Valid() & ~target_valid;
    cv::Mat3f c;
    view.colour.convertTo(c, CV_32F);
    c.copyTo(target, add);
    target_valid |= add;
  }
}

std::vector<double> RelativeSharpness(const FusionOptions& o, const std::vector<ViewRendering>& r,
                                      long surface_pixels) {
  const int n = int(r.size());
  // Squared grey gradients, after levelling: print's edges dominate them.
  std::vector<cv::Mat1f> energy(n);
  std::vector<cv::Mat1b> valid(n);
  for (int v = 0; v < n; ++v) {
    cv::Mat grey;
    cv::Mat1f gx, gy;
    cv::cvtColor(r[v].colour, grey, cv::COLOR_BGR2GRAY);
    grey.convertTo(grey, CV_32F);
    cv::Sobel(grey, gx, CV_32F, 1, 0);
    cv::Sobel(grey, gy, CV_32F, 0, 1);
    energy[v] = gx.mul(gx) + gy.mul(gy);
    // Off the edge of what a view sees, the black beyond would count as print.
    cv::erode(r[v].Valid(), valid[v], cv::Mat(), cv::Point(-1, -1), 3);
  }
  // log(E_j / E_k) on the pixels both resolve about equally finely: there the
  // ratio says which photo is blurred, whatever the print.
  const double band = std::log(o.sharpness_resolution_band);
  const long min_pixels = std::max<long>(500, long(0.01 * surface_pixels));
  Eigen::MatrixXd normal = Eigen::MatrixXd::Identity(n, n) * 1e-3;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < n; ++j)
    for (int k = j + 1; k < n; ++k) {
      double ej = 0, ek = 0;
      long count = 0;
      for (int y = 0; y < valid[j].rows; ++y) {
        const uchar* vj = valid[j].ptr<uchar>(y);
        const uchar* vk = valid[k].ptr<uchar>(y);
        const float* rj = r[j].resolution.ptr<float>(y);
        const float* rk = r[k].resolution.ptr<float>(y);
        const float* fj = energy[j].ptr<float>(y);
        const float* fk = energy[k].ptr<float>(y);
        for (int x = 0; x < valid[j].cols; ++x) {
          if (!vj[x] || !vk[x]) continue;
          const double cj = std::min<double>(rj[x], o.resolution_cap);
          const double ck = std::min<double>(rk[x], o.resolution_cap);
          if (std::abs(std::log(cj / ck)) > band) continue;
          ej += fj[x];
          ek += fk[x];
          ++count;
        }
      }
      // A blank overlap (paper noise alone) says nothing.
      if (count < min_pixels || std::min(ej, ek) < o.sharpness_min_energy * count) continue;
      const double m = std::log(ej / ek);
      const double w = std::sqrt(double(count));
      normal(j, j) += w, normal(k, k) += w, normal(j, k) -= w, normal(k, j) -= w;
      rhs(j) += w * m, rhs(k) -= w * m;
    }
  const Eigen::VectorXd g = normal.ldlt().solve(rhs);
  std::vector<double> sharpness(n, 1.0);
  const double best = g.maxCoeff(), tolerated = std::log(o.sharpness_tolerance);
  for (int v = 0; v < n; ++v)
    sharpness[v] = std::exp(-o.blur_weight * std::max(0.0, best - g(v) - tolerated));
  return sharpness;
}

}  // namespace docunfold::fusion_internal
