// Outline points from the sides' straight images: where every photo's
// epipolar lines run along a page side, the side's line in each photo places
// the samples the epipolar matching (edge_points.cc) could not.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "common/line_fit.h"
#include "common/statistics.h"
#include "stages/densify/densify_internal.h"

namespace docunfold::densify::detail {
namespace {

// The total-least-squares line through `pixels` as (a, b, c) with
// a x + b y + c = 0, (a, b) unit, and the RMS of their distances to it.
Eigen::Vector3d FitLine(const std::vector<Eigen::Vector2d>& pixels, double* rms) {
  const LineFit2d fit = FitLineTotalLeastSquares(pixels);
  *rms = fit.rms;
  return {fit.normal.x(), fit.normal.y(), -fit.normal.dot(fit.point)};
}

// The line most of `pixels` lie within `tolerance` of (a deterministic
// RANSAC over evenly spread pairs, then refitted to its inliers); false
// when fewer than `min_share` of them do.
bool RobustLine(const std::vector<Eigen::Vector2d>& pixels, double tolerance, double min_share,
                Eigen::Vector3d* line, double* rms, std::vector<Eigen::Vector2d>* inliers) {
  const int n = int(pixels.size());
  if (n < 10) return false;
  int best = 0;
  Eigen::Vector3d best_line = Eigen::Vector3d::Zero();
  const int stride = std::max(1, n / 40);
  for (int i = 0; i < n; i += stride)
    for (int j = i + n / 4; j < n; j += stride) {
      const Eigen::Vector2d d = pixels[j] - pixels[i];
      if (d.norm() < 1e-9) continue;
      const Eigen::Vector2d normal = Eigen::Vector2d(-d.y(), d.x()).normalized();
      const Eigen::Vector3d l(normal.x(), normal.y(), -normal.dot(pixels[i]));
      int count = 0;
      for (const auto& p : pixels) count += std::abs(l.head<2>().dot(p) + l(2)) <= tolerance;
      if (count > best) {
        best = count;
        best_line = l;
      }
    }
  if (best < min_share * n) return false;
  inliers->clear();
  for (const auto& p : pixels)
    if (std::abs(best_line.head<2>().dot(p) + best_line(2)) <= tolerance) inliers->push_back(p);
  *line = FitLine(*inliers, rms);
  return true;
}

// The world plane through `camera`'s centre that projects onto image line
// `line`: its unit normal.
Eigen::Vector3d PlaneNormal(const PinholeCamera& camera, const Eigen::Vector3d& line) {
  return (camera.R.transpose() * (camera.K.transpose() * line)).normalized();
}

// A photo's straight image of a page side: a point on it and its unit
// normal (pixels of the photo's working copy).
struct PhotoLine {
  const PinholeCamera* camera = nullptr;
  Eigen::Vector2d point, normal;
};

// The side's image in `view`: steps of the samples' polarity within
// side_line_reach_px of their epipolar segments, across the side's
// direction there, fitted with a line; nullopt when they make none, or
// its plane meets the reference's (`reference_normal`) at less than
// side_line_min_angle_deg and says nothing about depth.
std::optional<PhotoLine> SideLineInPhoto(const View& ref, const View& view,
                                         const std::vector<EdgeSample*>& left,
                                         const Eigen::Vector3d& reference_normal,
                                         const OutlineOptions& o) {
  std::vector<Eigen::Vector2d> steps;
  for (const EdgeSample* e : left) {
    const auto segment = EpipolarSegmentIn(ref, view, *e);
    if (!segment) continue;
    const Eigen::Vector2d a = segment->near, b = segment->far, across = segment->across;
    const double length = (b - a).norm();
    for (double s = 0; s <= length; s += 2) {
      const Eigen::Vector2d p = a + (length > 0 ? s / length : 0.0) * (b - a);
      double offset = 0, strength = 0;
      if (view.Inside(p) &&
          FindStep(view, p, across, o.side_line_reach_px, e->sign, &offset, &strength) &&
          strength >= o.min_contrast)
        steps.push_back(p + offset * across);
    }
  }
  Eigen::Vector3d line;
  double rms = 0;
  std::vector<Eigen::Vector2d> inliers;
  if (!RobustLine(steps, 1.0, o.side_line_min_share, &line, &rms, &inliers) ||
      int(inliers.size()) < o.side_line_min_samples || rms > o.side_line_max_rms_px)
    return std::nullopt;
  const double cos = std::abs(PlaneNormal(view.camera, line).dot(reference_normal));
  if (std::acos(std::min(1.0, cos)) * 180 / M_PI < o.side_line_min_angle_deg) return std::nullopt;
  return PhotoLine{&view.camera, -line(2) * line.head<2>(), line.head<2>()};
}

// A sample's depth from the lines `use` of `lines` (residuals across them
// only, as for a matched sample), and its residual across each (pixels).
bool DepthFromLines(const PinholeCamera& ref, const EdgeSample& e,
                    const std::vector<PhotoLine>& lines, const std::vector<int>& use, double* depth,
                    std::vector<double>* residuals) {
  std::vector<Observation> obs{{&ref, e.pixel}};
  std::vector<Eigen::Vector2d> normals;
  for (int k : use) {
    obs.push_back({lines[k].camera, lines[k].point});
    normals.push_back(lines[k].normal);
  }
  *depth = 0.5 * (e.near_depth + e.far_depth);
  double worst = 0, mean = 0;
  if (!DepthAcrossEdges(ref, e.pixel, obs, normals, depth, &worst, &mean, residuals)) return false;
  for (double& r : *residuals) r = std::abs(r);
  return true;
}

// How many pixels across the lines `use` a change of the sample's depth by
// its own size moves it (root sum of squares): half a pixel of bias in the
// lines moves the point 0.5 / this of its depth.
double LineSensitivity(const PinholeCamera& ref, const EdgeSample& e,
                       const std::vector<PhotoLine>& lines, const std::vector<int>& use,
                       double depth) {
  double sum = 0;
  const double h = 1e-6 * depth;
  for (int k : use) {
    const Eigen::Vector2d p0 = lines[k].camera->Project(ref.LiftAtDepth(e.pixel, depth));
    const Eigen::Vector2d p1 = lines[k].camera->Project(ref.LiftAtDepth(e.pixel, depth + h));
    sum += std::pow(lines[k].normal.dot(p1 - p0) / h * depth, 2);
  }
  return std::sqrt(sum);
}

// The largest set of `lines` (at least min_views - 1) that agree, by the
// largest of their median residuals over the samples `left`, within
// max_reprojection_px; ties go to the set that agrees best. A photo that
// disagrees saw another edge there (a fold's, where it sees the page's
// back). Past 8 photos only all of them are tried. Empty: none agree.
std::vector<int> AgreeingLines(const PinholeCamera& ref, const std::vector<PhotoLine>& lines,
                               const std::vector<EdgeSample*>& left, const OutlineOptions& o) {
  const int n = int(lines.size());
  std::vector<std::vector<int>> subsets;
  if (n > 8) {
    subsets.emplace_back(n);
    std::iota(subsets.back().begin(), subsets.back().end(), 0);
  } else {
    for (int mask = 1; mask < 1 << n; ++mask) {
      subsets.emplace_back();
      for (int k = 0; k < n; ++k)
        if (mask & (1 << k)) subsets.back().push_back(k);
    }
  }
  std::vector<int> use;
  double use_spread = HUGE_VAL;
  for (const std::vector<int>& pick : subsets) {
    if (int(pick.size()) + 1 < o.min_views || pick.size() < use.size()) continue;
    std::vector<std::vector<double>> per_line(pick.size());
    for (const EdgeSample* e : left) {
      double depth = 0;
      std::vector<double> residuals;
      if (!DepthFromLines(ref, *e, lines, pick, &depth, &residuals)) continue;
      for (size_t k = 0; k < pick.size(); ++k) per_line[k].push_back(residuals[k]);
    }
    double spread = 0;
    for (const auto& r : per_line) spread = std::max(spread, r.empty() ? HUGE_VAL : Median(r));
    if (spread > o.max_reprojection_px) continue;
    if (pick.size() > use.size() || spread < use_spread) {
      use = pick;
      use_spread = spread;
    }
  }
  return use;
}

}  // namespace

// Outline points of a straight real side whose samples the epipolar
// matching left without a point, where each photo's epipolar segments run
// along the side's image (a panel standing up at the end of a page lying
// flat, seen from above: every photo's rays graze it). No sample then has a
// crossing to match, but the side's image in each photo is still a straight
// step (SideLineInPhoto), and each sample's depth is where its ray meets the
// planes through the cameras and the lines that agree (AgreeingLines).
void AddSideLinePoints(const View& ref, const std::vector<View>& others,
                       std::vector<EdgeSample>* samples, const OutlineOptions& o,
                       const EdgeCheck& check, EdgeCounts* counts, PlyData* points) {
  for (int side = 0; side < 4; ++side) {
    std::vector<EdgeSample*> left;
    std::vector<Eigen::Vector2d> reference_pixels;
    for (EdgeSample& e : *samples) {
      if (e.side != side) continue;
      reference_pixels.push_back(e.pixel);
      if (!e.matched) left.push_back(&e);
    }
    if (int(left.size()) < o.side_line_min_samples) continue;
    double rms = 0;
    const Eigen::Vector3d reference_line = FitLine(reference_pixels, &rms);
    if (rms > o.side_line_max_rms_px) continue;
    const Eigen::Vector3d reference_normal = PlaneNormal(ref.camera, reference_line);
    std::vector<PhotoLine> lines;
    for (const View& view : others)
      if (auto line = SideLineInPhoto(ref, view, left, reference_normal, o)) lines.push_back(*line);
    if (int(lines.size()) + 1 < o.min_views) continue;
    const std::vector<int> use = AgreeingLines(ref.camera, lines, left, o);
    if (int(use.size()) + 1 < o.min_views) continue;
    for (EdgeSample* e : left) {
      double depth = 0;
      std::vector<double> residuals;
      if (!DepthFromLines(ref.camera, *e, lines, use, &depth, &residuals) ||
          *std::max_element(residuals.begin(), residuals.end()) > o.max_reprojection_px ||
          !check(*e, depth))
        continue;
      // Planes a few degrees apart put a sub-pixel bias of the lines (an
      // edge's blur or shadow, the same in every sample) far along the ray.
      if (o.side_line_bias_px / LineSensitivity(ref.camera, *e, lines, use, depth) >
          o.side_line_max_depth_error) {
        ++counts->side_line_weak;
        continue;
      }
      AppendPoint(ref.camera.LiftAtDepth(e->pixel, depth), {255, 0, 255}, int(use.size() + 1),
                  Median(residuals), PointSource::kOutline, points);
      e->matched = true;
      ++counts->points;
      ++counts->side_line_points;
    }
  }
}

}  // namespace docunfold::densify::detail
