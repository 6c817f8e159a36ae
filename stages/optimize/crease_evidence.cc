#include "stages/optimize/crease_evidence.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/isometry/isometry.h"

namespace docunfold::optimize {

CreaseMap CreaseEvidence(const cv::Mat& reference_bgr, const cv::Mat1b& reference_page,
                         const CreaseOptions& o) {
  CreaseMap map;
  cv::Mat gray;
  if (reference_bgr.channels() == 3) {
    cv::cvtColor(reference_bgr, gray, cv::COLOR_BGR2GRAY);
  } else {
    gray = reference_bgr;
  }
  cv::Mat1b page = reference_page;
  map.scale = std::min(1.0, double(o.max_side_px) / std::max(gray.cols, gray.rows));
  if (map.scale < 1) {
    cv::resize(gray, gray, cv::Size(), map.scale, map.scale, cv::INTER_AREA);
    cv::resize(reference_page, page, gray.size(), 0, 0, cv::INTER_NEAREST);
  }
  cv::Mat1f paper;
  gray.convertTo(paper, CV_32F);
  const int k = 2 * (o.ink_close_px / 2) + 1;
  cv::morphologyEx(paper, paper, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  cv::log(paper + 1.0f, paper);
  auto gradient = [&](double sigma, cv::Mat1f* gx, cv::Mat1f* gy) {
    cv::Mat1f blurred;
    cv::GaussianBlur(paper, blurred, cv::Size(), sigma);
    cv::Sobel(blurred, *gx, CV_32F, 1, 0, 3, 1.0 / 8);
    cv::Sobel(blurred, *gy, CV_32F, 0, 1, 3, 1.0 / 8);
  };
  cv::Mat1f fx, fy, cx, cy;
  gradient(o.fine_sigma_px, &fx, &fy);
  gradient(o.coarse_sigma_px, &cx, &cy);
  cv::Mat1b inner;
  const int m = 2 * int(std::ceil(o.outline_margin_px)) + 1;
  cv::erode(page, inner, cv::getStructuringElement(cv::MORPH_ELLIPSE, {m, m}));
  map.step = cv::Mat2f(paper.size(), cv::Vec2f(0, 0));
  for (int y = 0; y < paper.rows; ++y)
    for (int x = 0; x < paper.cols; ++x) {
      if (!inner(y, x)) continue;
      // The fine gradient less the coarse one's length along it: a ramp
      // gives the same at both scales, a step a sharper fine one.
      const cv::Vec2f f(fx(y, x), fy(y, x));
      const double lf = std::hypot(f[0], f[1]);
      if (lf <= 0) continue;
      const double lc = std::abs((cx(y, x) * f[0] + cy(y, x) * f[1]) / lf);
      const double s = std::max(0.0, lf - lc);
      map.step(y, x) = cv::Vec2f(float(f[0] / lf * s), float(f[1] / lf * s));
    }
  return map;
}

std::vector<double> CreaseFairWeights(const MeshPair& meshes, const PinholeCamera& reference,
                                      const CreaseMap& map, const CreaseOptions& o, int* spared) {
  const auto triplets = isometry::FairTriplets(meshes.grid);
  std::vector<double> weights(triplets.size(), 1.0);
  if (spared) *spared = 0;
  const cv::Mat2f& evidence = map.step;
  if (o.step <= 0 || evidence.empty()) return weights;
  for (size_t t = 0; t < triplets.size(); ++t) {
    const Eigen::Vector3d& a = meshes.mesh3d[size_t(triplets[t][0])];
    const Eigen::Vector3d& b = meshes.mesh3d[size_t(triplets[t][2])];
    if (reference.CamFromWorld(a).z() <= 0 || reference.CamFromWorld(b).z() <= 0) continue;
    const Eigen::Vector2d pa = map.scale * reference.Project(a),
                          pb = map.scale * reference.Project(b);
    const Eigen::Vector2d d = pb - pa;
    const double length = d.norm();
    if (!(length > 0)) continue;
    const Eigen::Vector2d dir = d / length;
    double step = 0;
    const int samples = std::max(2, int(std::ceil(length)));
    for (int i = 0; i <= samples; ++i) {
      const Eigen::Vector2d p = pa + d * (double(i) / samples);
      const int x = int(std::lround(p.x())), y = int(std::lround(p.y()));
      if (x < 0 || y < 0 || x >= evidence.cols || y >= evidence.rows) continue;
      const cv::Vec2f e = evidence(y, x);
      step = std::max(step, std::abs(e[0] * dir.x() + e[1] * dir.y()));
    }
    const double r = step / o.step;
    weights[t] = std::max(o.min_weight, 1 / (1 + r * r));
    if (spared && weights[t] < 0.5) ++*spared;
  }
  return weights;
}

}  // namespace docunfold::optimize
