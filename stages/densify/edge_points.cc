// Outline and shading-step points: edges of the reference view (the page's
// real sides; steps of blank paper on blurred copies) matched along their
// epipolar segments in the other photos and triangulated.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "common/point_index.h"
#include "common/statistics.h"
#include "stages/densify/densify_internal.h"

namespace docunfold::densify::detail {

bool FindStep(const View& view, const Eigen::Vector2d& c, const Eigen::Vector2d& n, double reach,
              int sign, double* offset, double* strength) {
  const int count = int(2 * reach / 0.5) + 1;
  std::vector<double> g(count, 0);
  int best = -1;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d p = c + (-reach + 0.5 * i) * n;
    if (!view.Inside(p)) continue;
    g[i] = sign * view.Gradient(p).dot(n);
    if (best < 0 || g[i] > g[best]) best = i;
  }
  if (best <= 0 || best >= count - 1 || g[best] <= 0) return false;
  *offset = -reach + 0.5 * (best + ParabolaPeak(g, best));
  *strength = g[best];
  return true;
}

std::optional<EpipolarSegment> EpipolarSegmentIn(const View& ref, const View& view,
                                                 const EdgeSample& e) {
  const Eigen::Vector3d A = view.camera.CamFromWorld(ref.camera.LiftAtDepth(e.pixel, e.near_depth));
  const Eigen::Vector3d B = view.camera.CamFromWorld(ref.camera.LiftAtDepth(e.pixel, e.far_depth));
  if (!(A.z() > 0) || !(B.z() > 0)) return std::nullopt;
  const double mid = 0.5 * (e.near_depth + e.far_depth);
  const Eigen::Vector2d at = view.camera.Project(ref.camera.LiftAtDepth(e.pixel, mid));
  const Eigen::Vector2d across =
      (view.camera.Project(ref.camera.LiftAtDepth(e.pixel + e.normal, mid)) - at).normalized();
  if (!across.allFinite()) return std::nullopt;
  return EpipolarSegment{view.camera.ProjectCam(A), view.camera.ProjectCam(B), across};
}

bool DepthAcrossEdges(const PinholeCamera& ref, const Eigen::Vector2d& pixel,
                      const std::vector<Observation>& obs,
                      const std::vector<Eigen::Vector2d>& normals, double* depth, double* worst,
                      double* mean, std::vector<double>* residuals_out) {
  auto residuals = [&](double d, std::vector<double>* r) {
    r->clear();
    const Eigen::Vector3d X = ref.LiftAtDepth(pixel, d);
    for (size_t k = 1; k < obs.size(); ++k) {
      const Eigen::Vector3d xc = obs[k].camera->CamFromWorld(X);
      if (!(xc.z() > 0)) return false;
      r->push_back(normals[k - 1].dot(obs[k].camera->ProjectCam(xc) - obs[k].pixel));
    }
    return true;
  };
  std::vector<double> r0, r1;
  if (!(*depth > 0)) return false;
  for (int iteration = 0; iteration < 8; ++iteration) {
    const double step = 1e-6 * *depth;
    if (!residuals(*depth, &r0) || !residuals(*depth + step, &r1)) return false;
    double jtj = 0, jtr = 0;
    for (size_t k = 0; k < r0.size(); ++k) {
      const double j = (r1[k] - r0[k]) / step;
      jtj += j * j;
      jtr += j * r0[k];
    }
    if (!(jtj > 0)) return false;
    const double delta = -jtr / jtj;
    *depth += delta;
    if (!(*depth > 0) || std::abs(delta) < 1e-9 * *depth) break;
  }
  if (!(*depth > 0) || !residuals(*depth, &r0)) return false;
  *worst = *mean = 0;
  for (const double r : r0) {
    *worst = std::max(*worst, std::abs(r));
    *mean += std::abs(r) / double(r0.size());
  }
  if (residuals_out) *residuals_out = r0;
  return true;
}

namespace {

// --- edges and their matching ----------------------------------------------

// Whether the step at c (grey rising along the unit `normal`) continues
// straight along the edge: a step of the same sign of at least
// `min_strength` within 1.5 px of the line through c, half and all of
// `reach` to either side. Texture of a table or carpet gives short gradient
// blobs, a page's edge or a fold a straight step.
bool StepContinues(const View& view, const Eigen::Vector2d& c, const Eigen::Vector2d& normal,
                   double reach, double min_strength) {
  const Eigen::Vector2d tangent(-normal.y(), normal.x());
  for (double along : {-reach, -reach / 2, reach / 2, reach}) {
    double offset = 0, strength = 0;
    if (!FindStep(view, c + along * tangent, normal, 1.5, 1, &offset, &strength) ||
        strength < min_strength)
      return false;
  }
  return true;
}

std::vector<EdgeSample> EdgeSamples(const View& ref, const Boundary& boundary,
                                    const cv::Mat1b& page, double scale, const OutlineOptions& o) {
  std::vector<EdgeSample> samples;
  std::array<Eigen::Vector2d, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = ScalePixel(boundary.corners[i], scale);
  for (int s = 0; s < 4; ++s) {
    if (!boundary.sides[s].real) continue;
    const auto& side = boundary.sides[s].points;
    double walked = 0;  // arc length of the side before segment k
    for (size_t k = 0; k + 1 < side.size(); ++k) {
      const Eigen::Vector2d a = ScalePixel(side[k], scale), b = ScalePixel(side[k + 1], scale);
      const double length = (b - a).norm();
      if (length < 1e-9) continue;
      const Eigen::Vector2d t = (b - a) / length;
      // Samples every step_px of arc length along the whole side.
      for (double u = std::fmod(o.step_px - std::fmod(walked, o.step_px), o.step_px); u < length;
           u += o.step_px) {
        const Eigen::Vector2d p = a + u * t;
        bool near_corner = false;
        for (const auto& c : corners) near_corner |= (p - c).norm() < o.corner_gap_px;
        if (near_corner) continue;
        Eigen::Vector2d n(-t.y(), t.x());
        const Eigen::Vector2d probe = p + 4 * n;
        if (ref.Inside(probe, 0) && page(int(probe.y()), int(probe.x()))) n = -n;
        double off_up = 0, up = 0, off_down = 0, down = 0;
        const bool rises = FindStep(ref, p, n, 5, 1, &off_up, &up);
        const bool falls = FindStep(ref, p, n, 5, -1, &off_down, &down);
        if (!rises && !falls) continue;
        const bool use_rise = rises && (!falls || up >= down);
        if ((use_rise ? up : down) < o.min_contrast) continue;
        EdgeSample e;
        e.pixel = p + (use_rise ? off_up : off_down) * n;
        e.normal = n;
        e.sign = use_rise ? 1 : -1;
        e.side = s;
        samples.push_back(e);
      }
      walked += length;
    }
  }
  return samples;
}

// Affine fit of 1/depth to the known points within `radius` of `pixel` that
// `keep` accepts (given their offset from it): 1/depth = c0 du + c1 dv + c2.
// False when fewer than 6 points there span an area.
template <class Keep>
bool FitInverseDepth(const Eigen::Vector2d& pixel, double radius,
                     const std::vector<Eigen::Vector2d>& known_pixels,
                     const std::vector<double>& known_depths, const Keep& keep,
                     Eigen::Vector3d* c) {
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  int near = 0;
  for (size_t i = 0; i < known_pixels.size(); ++i) {
    const Eigen::Vector2d d = known_pixels[i] - pixel;
    if (d.squaredNorm() > radius * radius || !keep(d)) continue;
    const Eigen::Vector3d a(d.x(), d.y(), 1);
    ata += a * a.transpose();
    atb += a / known_depths[i];
    ++near;
  }
  if (near < 6 || !(std::abs(ata.determinant()) > 1e-6 * std::pow(ata.trace(), 3))) return false;
  *c = ata.ldlt().solve(atb);
  return true;
}

// Whether `depth` at `pixel` continues the surface of the known points
// within continuity_radius_px (an affine fit of 1/depth, when at least 6 are
// there and they span an area) to max_depth_jump of the depth.
bool ContinuesSurface(const Eigen::Vector2d& pixel, double depth,
                      const std::vector<Eigen::Vector2d>& known_pixels,
                      const std::vector<double>& known_depths, const OutlineOptions& o) {
  Eigen::Vector3d c;
  if (!FitInverseDepth(
          pixel, o.continuity_radius_px, known_pixels, known_depths,
          [](const Eigen::Vector2d&) { return true; }, &c))
    return true;
  const double inverse_depth = c(2);
  return !(inverse_depth > 0 && std::abs(1 / inverse_depth - depth) > o.max_depth_jump * depth);
}

// Whether a triangulated edge sample at `depth` (reference camera) may be kept.
using EdgeCheck = std::function<bool(const EdgeSample&, double depth)>;

// Sets each sample's depth range: that of its `depth_neighbours` nearest
// known points in the reference image, widened by depth_margin on both
// sides; empties its candidates (one list per view index).
void SetDepthRanges(const std::vector<Eigen::Vector2d>& known_pixels,
                    const std::vector<double>& known_depths, int num_views, const OutlineOptions& o,
                    std::vector<EdgeSample>* samples) {
  std::unique_ptr<PointIndex2d> index;
  if (!known_pixels.empty()) index = std::make_unique<PointIndex2d>(known_pixels);
  const int k = int(std::min<size_t>(std::max(1, o.depth_neighbours), known_pixels.size()));
  for (EdgeSample& e : *samples) {
    double lo = std::numeric_limits<double>::infinity(), hi = 0;
    if (index)
      for (const auto& [i, squared_distance] : index->Nearest(e.pixel, k)) {
        lo = std::min(lo, known_depths[i]);
        hi = std::max(hi, known_depths[i]);
      }
    e.near_depth = lo * (1 - o.depth_margin);
    e.far_depth = hi * (1 + o.depth_margin);
    e.candidates.assign(num_views, {});
  }
}

// Collects each sample's candidates in every other view: steps of the same
// sign crossing its epipolar segment (between its near and far depth) at
// least min_epipolar_angle_deg, continuing straight along the edge.
// `stats`, when given, counts them per view.
void FindCandidates(const View& ref, const std::vector<View>& others, const OutlineOptions& o,
                    std::vector<EdgeSample>* samples, std::vector<ViewStats>* stats) {
  const double min_cos = std::sin(o.min_epipolar_angle_deg * M_PI / 180);
  for (const View& view : others) {
    for (EdgeSample& e : *samples) {
      const auto segment = EpipolarSegmentIn(ref, view, e);
      if (!segment) continue;
      const Eigen::Vector2d a = segment->near, b = segment->far;
      const double length = (b - a).norm();
      if (length < 1) continue;
      const Eigen::Vector2d dir = (b - a) / length;
      // The across direction serves only the crossing angle and the
      // gradient's direction.
      const Eigen::Vector2d nj = segment->across;
      const double cos_cross = nj.dot(dir);
      if (std::abs(cos_cross) < min_cos) continue;
      const int sign_along = e.sign * (cos_cross > 0 ? 1 : -1);
      const int count = int(length / 0.5) + 1;
      std::vector<double> g(count, 0);
      for (int i = 0; i < count; ++i) {
        const Eigen::Vector2d p = a + 0.5 * i * dir;
        if (view.Inside(p)) g[i] = sign_along * view.Gradient(p).dot(dir);
      }
      const double floor = o.min_contrast * std::abs(cos_cross);
      for (int i = 1; i + 1 < count; ++i) {
        if (g[i] < floor || g[i] < g[i - 1] || g[i] <= g[i + 1]) continue;
        const Eigen::Vector2d c = a + 0.5 * (i + ParabolaPeak(g, i)) * dir;
        const Eigen::Vector2d grad = view.Gradient(c);
        if (e.sign * grad.normalized().dot(nj) < 0.85) continue;  // not this edge's direction
        // The step continues along the edge as this image shows it (a
        // tangent predicted from the reference is off where the edge
        // recedes in depth: set07's tilted panel).
        const Eigen::Vector2d normal = grad.normalized();  // grey rises along it
        if (!StepContinues(view, c, normal, o.straight_px, 0.5 * g[i] * std::abs(cos_cross)))
          continue;
        e.candidates[view.index].push_back({c, normal});
        if (stats) ++(*stats)[view.index].outline_candidates;
      }
    }
  }
}

// A depth hypothesis for an edge sample: one candidate triangulated with the
// reference, and the candidates of the other views where it projects.
struct Hypothesis {
  Eigen::Vector3d point;
  std::vector<Observation> obs;          // the reference first
  std::vector<int> views;                // of obs[1...]
  std::vector<Eigen::Vector2d> normals;  // of obs[1...]
};

// Every candidate of `e` as a depth hypothesis; its support is the number of
// other views with a candidate within agree_px of where that depth projects.
// `view_of` maps view indices to the views.
std::vector<Hypothesis> Hypotheses(const EdgeSample& e, const View& ref,
                                   const std::vector<const View*>& view_of, int num_views,
                                   const OutlineOptions& o) {
  std::vector<Hypothesis> hypotheses;
  for (int vi = 0; vi < num_views; ++vi) {
    for (const EdgeMatch& c : e.candidates[vi]) {
      Hypothesis h;
      h.point = Triangulate({&ref.camera, &view_of[vi]->camera}, {e.pixel, c.pixel});
      if (!h.point.allFinite()) continue;
      h.obs = {{&ref.camera, e.pixel}, {&view_of[vi]->camera, c.pixel}};
      h.views = {vi};
      h.normals = {c.normal};
      for (int vk = 0; vk < num_views; ++vk) {
        if (vk == vi || e.candidates[vk].empty()) continue;
        const Eigen::Vector3d xc = view_of[vk]->camera.CamFromWorld(h.point);
        if (!(xc.z() > 0)) continue;
        const Eigen::Vector2d expected = view_of[vk]->camera.ProjectCam(xc);
        const EdgeMatch* nearest = nullptr;
        double nearest_distance = o.agree_px;
        for (const EdgeMatch& ck : e.candidates[vk]) {
          const double d = (ck.pixel - expected).norm();
          if (d < nearest_distance) {
            nearest_distance = d;
            nearest = &ck;
          }
        }
        if (nearest) {
          h.obs.push_back({&view_of[vk]->camera, nearest->pixel});
          h.views.push_back(vk);
          h.normals.push_back(nearest->normal);
        }
      }
      hypotheses.push_back(std::move(h));
    }
  }
  return hypotheses;
}

// Whether a hypothesis at a clearly different depth (its points 3 px apart
// in some view) is as well supported as hypotheses[best].
bool Ambiguous(const std::vector<Hypothesis>& hypotheses, int best,
               const std::vector<View>& others) {
  bool ambiguous = false;
  for (size_t h = 0; h < hypotheses.size() && !ambiguous; ++h) {
    if (hypotheses[h].obs.size() < hypotheses[best].obs.size()) continue;
    double apart = 0;
    for (const View& view : others) {
      const Eigen::Vector3d p = view.camera.CamFromWorld(hypotheses[h].point);
      const Eigen::Vector3d q = view.camera.CamFromWorld(hypotheses[best].point);
      if (p.z() > 0 && q.z() > 0)
        apart = std::max(apart, (view.camera.ProjectCam(p) - view.camera.ProjectCam(q)).norm());
    }
    ambiguous = apart > 3;
  }
  return ambiguous;
}

// Matches edge samples of the reference along their epipolar segments in the
// other views (steps of the same sign crossing them, continuing straight
// along the edge), triangulates those enough views agree on unambiguously,
// and appends the points `check` accepts, with `source` and `colour`.
// `stats`, when given, counts candidates and votes per view.
void MatchEdgeSamples(const View& ref, const std::vector<View>& others, int num_views,
                      std::vector<EdgeSample>* samples_in,
                      const std::vector<Eigen::Vector2d>& known_pixels,
                      const std::vector<double>& known_depths, const OutlineOptions& o,
                      const EdgeCheck& check, PointSource source,
                      const std::array<uint8_t, 3>& colour, EdgeCounts* counts,
                      std::vector<ViewStats>* stats, PlyData* points) {
  std::vector<EdgeSample>& samples = *samples_in;
  SetDepthRanges(known_pixels, known_depths, num_views, o, &samples);
  FindCandidates(ref, others, o, &samples, stats);

  const std::vector<const View*> view_of = [&] {
    std::vector<const View*> v(num_views, nullptr);
    for (const View& view : others) v[view.index] = &view;
    return v;
  }();
  for (EdgeSample& e : samples) {
    const std::vector<Hypothesis> hypotheses = Hypotheses(e, ref, view_of, num_views, o);
    int best = -1;
    for (size_t h = 0; h < hypotheses.size(); ++h)
      if (best < 0 || hypotheses[h].obs.size() > hypotheses[best].obs.size()) best = int(h);
    if (best < 0 || int(hypotheses[best].obs.size()) < o.min_views) {
      ++counts->unmatched;
      continue;
    }
    if (Ambiguous(hypotheses, best, others)) {
      ++counts->ambiguous;
      continue;
    }
    const Hypothesis& h = hypotheses[best];
    double depth = ref.camera.CamFromWorld(h.point).z(), worst = 0, error = 0;
    if (!DepthAcrossEdges(ref.camera, e.pixel, h.obs, h.normals, &depth, &worst, &error) ||
        worst > o.max_reprojection_px) {
      ++counts->unmatched;
      continue;
    }
    if (!check(e, depth)) {
      ++counts->off_surface;
      continue;
    }
    AppendPoint(ref.camera.LiftAtDepth(e.pixel, depth), colour, int(h.obs.size()), error, source,
                points);
    e.matched = true;
    if (stats)
      for (int vi : h.views) ++(*stats)[vi].outline_votes;
    ++counts->points;
  }
}

// --- shading steps -----------------------------------------------------------

// `view` with the gradient of a copy blurred by `sigma` instead: print is
// gone from it, the shading of folds is not.
View BlurredView(const View& view, double sigma) {
  View v = view;
  // New buffers: the copy's gx and gy share the original's, which Sobel
  // would otherwise overwrite.
  v.gx = cv::Mat1f();
  v.gy = cv::Mat1f();
  cv::Mat blurred;
  cv::GaussianBlur(view.grey, blurred, cv::Size(0, 0), sigma);
  cv::Sobel(blurred, v.gx, CV_32F, 1, 0, 3, 0.125);
  cv::Sobel(blurred, v.gy, CV_32F, 0, 1, 3, 0.125);
  return v;
}

// Steps of the blurred reference inside the page, at least
// `outline_gap_px` from its outline: the strongest ridge pixel of the
// gradient (non-maximum suppressed across the step) in each `step_px` cell,
// where it reaches `min_contrast` and continues as a step along its
// direction. Normals point the way grey rises (sign +1).
std::vector<EdgeSample> StepSamples(const View& blurred_ref, const cv::Mat1b& page,
                                    const std::vector<Eigen::Vector2d>& known_pixels,
                                    const StepOptions& o, double straight_px) {
  std::unique_ptr<PointIndex2d> known;
  if (o.min_point_gap_px > 0 && !known_pixels.empty())
    known = std::make_unique<PointIndex2d>(known_pixels);
  cv::Mat1b inside;
  const int gap = std::max(1, int(std::lround(o.outline_gap_px)));
  cv::erode(page, inside,
            cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * gap + 1, 2 * gap + 1)));
  const cv::Mat1f &gx = blurred_ref.gx, &gy = blurred_ref.gy;
  cv::Mat1f magnitude;
  cv::magnitude(gx, gy, magnitude);
  const int cell = std::max(1, int(std::lround(o.step_px)));
  const int cells_x = (page.cols + cell - 1) / cell;
  std::vector<std::pair<float, cv::Point>> best(size_t(cells_x) * ((page.rows + cell - 1) / cell),
                                                {0.f, cv::Point(-1, -1)});
  for (int y = 1; y + 1 < page.rows; ++y)
    for (int x = 1; x + 1 < page.cols; ++x) {
      const float m = magnitude(y, x);
      if (m < o.min_contrast || !inside(y, x)) continue;
      // Neighbours across the step: the gradient's direction rounded to 45
      // degrees, modulo 180 (0, 45, 90, 135 degrees).
      static constexpr int kAcross[4][2] = {{1, 0}, {1, 1}, {0, 1}, {1, -1}};
      const double angle = std::atan2(gy(y, x), gx(y, x));
      const int q = int(std::lround(angle / (M_PI / 4))) & 3;
      const int dx = kAcross[q][0], dy = kAcross[q][1];
      if (m < magnitude(y + dy, x + dx) || m < magnitude(y - dy, x - dx)) continue;
      auto& b = best[size_t(y / cell) * cells_x + x / cell];
      if (m > b.first) b = {m, cv::Point(x, y)};
    }
  std::vector<EdgeSample> samples;
  for (const auto& [m, p] : best) {
    if (p.x < 0) continue;
    const Eigen::Vector2d c(p.x, p.y);
    if (known && known->Nearest(c, 1).front().second < o.min_point_gap_px * o.min_point_gap_px)
      continue;
    const Eigen::Vector2d n = blurred_ref.Gradient(c).normalized();
    if (!n.allFinite()) continue;
    double offset = 0, strength = 0;
    if (!FindStep(blurred_ref, c, n, 2, 1, &offset, &strength)) continue;
    const Eigen::Vector2d at = c + offset * n;
    if (!StepContinues(blurred_ref, at, n, straight_px, 0.5 * strength)) continue;
    EdgeSample e;
    e.pixel = at;
    e.normal = n;
    e.sign = 1;
    samples.push_back(e);
  }
  return samples;
}

// The surface of the known points within `radius` of `pixel` on one side of
// the line through it with normal `normal` (side +1 or -1), by an affine
// fit of 1/depth (exact on a plane): its depth at `pixel` and |cos| of the
// angle between the reference ray there and the fitted plane's normal.
// False when fewer than 6 points there span an area.
bool SideSurface(const PinholeCamera& camera, const Eigen::Vector2d& pixel,
                 const Eigen::Vector2d& normal, int side, double radius,
                 const std::vector<Eigen::Vector2d>& known_pixels,
                 const std::vector<double>& known_depths, double* depth, double* cos_ray) {
  Eigen::Vector3d c;  // 1/z = c0 du + c1 dv + c2
  if (!FitInverseDepth(
          pixel, radius, known_pixels, known_depths,
          [&](const Eigen::Vector2d& d) { return side * d.dot(normal) >= 1; }, &c))
    return false;
  if (!(c(2) > 0)) return false;
  *depth = 1 / c(2);
  // 1/z = n.(K^-1 [u v 1]) / d for the plane n.X = d: n ~ K^T (c0, c1, c2 - c0 u - c1 v).
  const Eigen::Vector3d plane =
      camera.K.transpose() *
      Eigen::Vector3d(c(0), c(1), c(2) - c(0) * pixel.x() - c(1) * pixel.y());
  const Eigen::Vector3d ray = camera.CamRay(pixel);
  *cos_ray = std::abs(plane.normalized().dot(ray.normalized()));
  return true;
}

}  // namespace

void AddOutlinePoints(const View& ref, const std::vector<View>& others, int num_views,
                      const Boundary& boundary, const cv::Mat1b& page,
                      const std::vector<Eigen::Vector2d>& known_pixels,
                      const std::vector<double>& known_depths, const OutlineOptions& o,
                      DensifyResult* result) {
  if (known_pixels.empty()) return;
  std::vector<EdgeSample> samples = EdgeSamples(ref, boundary, page, result->working_scale, o);
  result->outline.samples = int(samples.size());
  MatchEdgeSamples(
      ref, others, num_views, &samples, known_pixels, known_depths, o,
      [&](const EdgeSample& e, double depth) {
        return ContinuesSurface(e.pixel, depth, known_pixels, known_depths, o);
      },
      PointSource::kOutline, {255, 0, 255}, &result->outline, &result->views, &result->points);
  if (o.side_lines)
    AddSideLinePoints(
        ref, others, &samples, o,
        [&](const EdgeSample& e, double depth) {
          return ContinuesSurface(e.pixel, depth, known_pixels, known_depths, o);
        },
        &result->outline, &result->points);
}

// Pixels and depths in `camera` of `page_points` and of the points made so far
// (`points` from `first_new` on): what the edge matching searches around.
void KnownPoints(const PinholeCamera& camera, const std::vector<Eigen::Vector3d>& page_points,
                 const PlyData& points, size_t first_new, std::vector<Eigen::Vector2d>* pixels,
                 std::vector<double>* depths) {
  auto add = [&](const Eigen::Vector3d& X) {
    const Eigen::Vector3d xc = camera.CamFromWorld(X);
    if (!(xc.z() > 0)) return;
    pixels->push_back(camera.ProjectCam(xc));
    depths->push_back(xc.z());
  };
  for (const Eigen::Vector3d& X : page_points) add(X);
  for (size_t i = first_new; i < points.vertices.size(); ++i) add(points.vertices[i]);
}

void AddStepPoints(const View& ref, const std::vector<View>& others, int num_views,
                   const cv::Mat1b& page, const std::vector<Eigen::Vector2d>& known_pixels,
                   const std::vector<double>& known_depths, const StepOptions& so,
                   const OutlineOptions& outline, DensifyResult* result) {
  if (known_pixels.empty()) return;
  const View blurred_ref = BlurredView(ref, so.blur_px);
  std::vector<View> blurred;
  for (const View& v : others) blurred.push_back(BlurredView(v, so.blur_px));
  // The outline's matching, but with the step's own contrast and views.
  OutlineOptions o = outline;
  o.min_contrast = so.min_contrast;
  o.min_views = so.min_views;
  std::vector<EdgeSample> samples = StepSamples(blurred_ref, page, known_pixels, so, o.straight_px);
  result->steps.samples = int(samples.size());
  MatchEdgeSamples(
      blurred_ref, blurred, num_views, &samples, known_pixels, known_depths, o,
      [&](const EdgeSample& e, double depth) {
        // On the surface of the points on each side of the step that has
        // them (a fold's crease lies on both panels; a silhouette does not),
        // and neither side seen edge-on (a fold seen edge-on in the
        // reference is its silhouette there, matched elsewhere in the
        // others).
        auto on_sides = [&](double radius, int* fitted) {
          *fitted = 0;
          for (const int side : {1, -1}) {
            double d = 0, cos_ray = 0;
            if (!SideSurface(ref.camera, e.pixel, e.normal, side, radius, known_pixels,
                             known_depths, &d, &cos_ray))
              continue;
            ++*fitted;
            if (std::abs(d - depth) > so.max_depth_jump * depth || cos_ray < so.min_side_cos)
              return false;
          }
          return true;
        };
        int fitted = 0;
        if (!on_sides(so.side_radius_px, &fitted)) return false;
        if (fitted > 0) return true;
        // Without points next to it, against the surface further out.
        return on_sides(so.unsupported_radius_factor * so.side_radius_px, &fitted);
      },
      PointSource::kStep, {255, 255, 0}, &result->steps, nullptr, &result->points);
}

}  // namespace docunfold::densify::detail
