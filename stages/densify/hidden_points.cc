// The sfm points the reference view shows in another colour: behind the page.
#include <algorithm>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "common/statistics.h"
#include "stages/densify/densify.h"

namespace docunfold::densify {

std::vector<bool> HiddenInReference(const std::vector<Eigen::Vector3d>& points,
                                    const std::vector<std::array<uint8_t, 3>>& colours,
                                    const std::vector<int>& indices, const PinholeCamera& camera,
                                    const cv::Mat& reference, const HiddenOptions& o) {
  std::vector<bool> hidden(indices.size(), false);
  if (colours.size() != points.size() || reference.empty() || indices.empty()) return hidden;
  // A cloud whose points all carry one colour (a writer's default) tells nothing.
  if (std::all_of(indices.begin(), indices.end(),
                  [&](int i) { return colours[i] == colours[indices[0]]; }))
    return hidden;
  // Projections and the exposure gain (median of reference / point, per channel).
  std::vector<cv::Point> pixel(indices.size(), cv::Point(-1, -1));
  std::array<std::vector<double>, 3> ratios;
  for (size_t k = 0; k < indices.size(); ++k) {
    const Eigen::Vector3d xc = camera.CamFromWorld(points[indices[k]]);
    if (!(xc.z() > 0)) continue;
    const Eigen::Vector2d p = camera.ProjectCam(xc);
    const long u = std::lround(p.x()), v = std::lround(p.y());
    if (u < 0 || v < 0 || u >= reference.cols || v >= reference.rows) continue;
    pixel[k] = cv::Point(int(u), int(v));
    const cv::Vec3b bgr = reference.at<cv::Vec3b>(pixel[k]);
    const std::array<uint8_t, 3>& rgb = colours[indices[k]];
    for (int c = 0; c < 3; ++c) ratios[c].push_back((bgr[2 - c] + 1.0) / (rgb[c] + 1.0));
  }
  if (ratios[0].empty()) return hidden;
  std::array<double, 3> gain{};
  for (int c = 0; c < 3; ++c) gain[c] = Median(std::move(ratios[c]));
  cv::Mat lab;
  cv::cvtColor(reference, lab, cv::COLOR_BGR2Lab);
  // The points' colours at the reference's exposure, in Lab (one conversion).
  cv::Mat3b point_lab(int(indices.size()), 1);
  for (size_t k = 0; k < indices.size(); ++k) {
    const std::array<uint8_t, 3>& rgb = colours[indices[k]];
    for (int c = 0; c < 3; ++c)
      point_lab(int(k), 0)[2 - c] = cv::saturate_cast<uint8_t>(rgb[c] * gain[c]);
  }
  cv::cvtColor(point_lab, point_lab, cv::COLOR_BGR2Lab);
  const int w = std::max(0, o.window_px);
  for (size_t k = 0; k < indices.size(); ++k) {
    if (pixel[k].x < 0) continue;
    const cv::Vec3d a = point_lab(int(k), 0);
    double nearest = std::numeric_limits<double>::infinity();
    for (int v = std::max(0, pixel[k].y - w); v <= std::min(lab.rows - 1, pixel[k].y + w); ++v)
      for (int u = std::max(0, pixel[k].x - w); u <= std::min(lab.cols - 1, pixel[k].x + w); ++u)
        nearest = std::min(nearest, cv::norm(a - cv::Vec3d(lab.at<cv::Vec3b>(v, u))));
    hidden[k] = nearest > o.max_colour_distance;
  }
  return hidden;
}

}  // namespace docunfold::densify
