// Swept points: a depth sweep along the reference's rays around the surface
// of the points found so far. Each candidate's reference patch is carried
// into the other photos through the plane of that surface at a series of
// depths and scored by NCC; the best-supported depth becomes a point.
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "common/raster.h"
#include "common/statistics.h"
#include "stages/densify/densify_internal.h"

namespace docunfold::densify::detail {
namespace {

struct Candidate {
  Eigen::Vector2d pixel;     // working-copy reference pixel
  double surface_depth = 0;  // of the surface along its ray
  double depth = 0;          // the sweep's, when `found`
  bool found = false;
};

// Zero-mean normalised cross-correlation of two equally long patches; -1
// when either is flat. (cv::matchTemplate does the same, but a Mat pair per
// call costs more than the sum over 81 pixels, and the sweep makes millions.)
double Ncc(const std::vector<float>& a, const std::vector<float>& b) {
  const size_t n = a.size();
  double mean_a = 0, mean_b = 0;
  for (size_t i = 0; i < n; ++i) mean_a += a[i], mean_b += b[i];
  mean_a /= double(n), mean_b /= double(n);
  double ab = 0, aa = 0, bb = 0;
  for (size_t i = 0; i < n; ++i) {
    const double da = a[i] - mean_a, db = b[i] - mean_b;
    ab += da * db, aa += da * da, bb += db * db;
  }
  if (aa < 1e-6 || bb < 1e-6) return -1;
  return ab / std::sqrt(aa * bb);
}

// The surface of the `known` points as a triangle mesh (world frame): a grid
// of `grid_px` over the region grown by 4 px, each vertex on its pixel's ray
// at DepthField's planar depth.
void PointsSurface(const View& ref, const cv::Mat1b& region,
                   const std::vector<Eigen::Vector3d>& known, const SweepOptions& o,
                   std::vector<Eigen::Vector3d>* vertices, std::vector<Triangle>* triangles) {
  const std::unique_ptr<DepthField> surface =
      SurfaceOfPoints(ref.camera, known, o.surface_neighbours, 2 * o.surface_grid_px);
  if (!surface) return;
  const DepthField& depth = *surface;
  cv::Mat1b grown;
  cv::dilate(region, grown, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(9, 9)));
  const cv::Rect box = cv::boundingRect(grown);
  const int g = std::max(1, int(o.surface_grid_px));
  const int gw = box.width / g + 2, gh = box.height / g + 2;
  const Eigen::Matrix3d k_inv = ref.camera.K.inverse();
  std::vector<int> index(size_t(gw) * gh, -1);
  for (int j = 0; j < gh; ++j)
    for (int i = 0; i < gw; ++i) {
      const int u = box.x + i * g, v = box.y + j * g;
      if (!grown(std::min(v, grown.rows - 1), std::min(u, grown.cols - 1))) continue;
      const double d = depth.At(Eigen::Vector2d(u, v));
      if (!(d > 0) || !std::isfinite(d)) continue;
      const Eigen::Vector3d ray = k_inv * Eigen::Vector3d(u, v, 1);
      index[j * gw + i] = int(vertices->size());
      vertices->push_back(ref.camera.R.transpose() * (ray * (d / ray.z()) - ref.camera.t));
    }
  for (int j = 0; j + 1 < gh; ++j)
    for (int i = 0; i + 1 < gw; ++i) {
      const int a = index[j * gw + i], b = index[j * gw + i + 1], c = index[(j + 1) * gw + i + 1],
                d = index[(j + 1) * gw + i];
      if (a < 0 || b < 0 || c < 0 || d < 0) continue;
      triangles->push_back({a, b, c});
      triangles->push_back({a, c, d});
    }
}

// Reference pixels worth sweeping: on the `step_px` grid, the patch inside
// `page` by `edge_gap_px`, at least `min_gap_px` from every known point,
// printed (grey variance) and two-dimensional (corner strength and the
// structure tensor's isotropy), and on the surface.
std::vector<Candidate> Candidates(const View& ref, const cv::Mat1b& page,
                                  const std::vector<Eigen::Vector3d>& known,
                                  const RasterResult& ref_raster, const SweepOptions& o) {
  const int r = o.patch_radius;
  cv::Mat1b free_of_points(page.size(), uchar(255));
  for (const Eigen::Vector3d& X : known) {
    const Eigen::Vector3d c = ref.camera.CamFromWorld(X);
    if (!(c.z() > 0)) continue;
    const Eigen::Vector2d p = ref.camera.ProjectCam(c);
    const int u = int(std::lround(p.x())), v = int(std::lround(p.y()));
    if (u >= 0 && v >= 0 && u < page.cols && v < page.rows) free_of_points(v, u) = 0;
  }
  cv::Mat1f gap;
  cv::distanceTransform(free_of_points, gap, cv::DIST_L2, 5);
  cv::Mat1b inner;
  const int margin = 2 * (r + int(o.edge_gap_px)) + 1;
  // Past the photo's edge is not page (erode's default border is): where the
  // photo cuts the page off, a patch must still lie inside the photo.
  cv::erode(page, inner, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(margin, margin)),
            cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));

  cv::Mat1f grey, mean, mean_sq;
  ref.grey.convertTo(grey, CV_32F);
  cv::blur(grey, mean, cv::Size(2 * r + 1, 2 * r + 1));
  cv::blur(grey.mul(grey), mean_sq, cv::Size(2 * r + 1, 2 * r + 1));
  double min_corner = 0;
  const cv::Mat1f corner = CornerStrength(ref.grey, page, o.min_corner, &min_corner);
  if (corner.empty()) return {};
  cv::Mat eigen;  // per pixel: l1, l2, eigenvectors
  cv::cornerEigenValsAndVecs(ref.grey, eigen, o.isotropy_window, 3);

  std::vector<Candidate> candidates;
  const int step = std::max(1, int(o.step_px));
  for (int v = 0; v < page.rows; v += step)
    for (int u = 0; u < page.cols; u += step) {
      if (!inner(v, u) || gap(v, u) < o.min_gap_px) continue;
      if (mean_sq(v, u) - mean(v, u) * mean(v, u) < o.min_variance) continue;
      if (corner(v, u) < min_corner) continue;
      const cv::Vec6f e = eigen.at<cv::Vec6f>(v, u);
      if (!(e[1] >= o.min_isotropy * e[0])) continue;
      const float d = ref_raster.depth(v, u);
      if (std::isfinite(d)) candidates.push_back({Eigen::Vector2d(u, v), d});
    }
  return candidates;
}

// Sweeps one candidate; sets its depth and `found` when the peak is
// supported by two photos and unique.
void Sweep(const View& ref, const std::vector<View>& others,
           const std::vector<Eigen::Vector3d>& surface_vertices,
           const std::vector<Triangle>& surface_triangles, const RasterResult& ref_raster,
           const std::vector<RasterResult>& rasters, const SweepOptions& o, Candidate* c) {
  const int r = o.patch_radius;
  const int steps = std::max(3, o.depth_steps);
  const int u = int(c->pixel.x()), v = int(c->pixel.y());
  std::vector<float> ref_patch, patch;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) ref_patch.push_back(ref.grey(v + dy, u + dx));
  // The surface's plane at the candidate, in the reference camera's frame.
  const Triangle& t = surface_triangles[ref_raster.face(v, u)];
  const Eigen::Vector3d a = ref.camera.CamFromWorld(surface_vertices[t[0]]),
                        b = ref.camera.CamFromWorld(surface_vertices[t[1]]),
                        e = ref.camera.CamFromWorld(surface_vertices[t[2]]);
  Eigen::Vector3d n = (b - a).cross(e - a);
  if (n.norm() < 1e-12) return;
  n.normalize();
  const Eigen::Matrix3d k_inv = ref.camera.K.inverse();
  const Eigen::Vector3d ray = k_inv * Eigen::Vector3d(u, v, 1);
  const double ref_facing = n.dot(ray);
  const Eigen::Vector3d surface_world =
      ref.camera.R.transpose() * (ray * (c->surface_depth / ray.z()) - ref.camera.t);
  const Eigen::Vector3d n_world = ref.camera.R.transpose() * n;
  const double inv_far = 1.0 / (c->surface_depth * (1 + o.depth_range)),
               inv_near = 1.0 / (c->surface_depth * (1 - o.depth_range));
  const auto inverse_depth = [&](int s) {
    return inv_far + (inv_near - inv_far) * s / (steps - 1);
  };

  // ncc[k][s]: photo k at depth step s (-1 where it does not see the patch).
  std::vector<std::vector<double>> ncc(others.size(), std::vector<double>(steps, -1));
  for (size_t k = 0; k < others.size(); ++k) {
    const View& view = others[k];
    // The photo sees the surface there (its depth buffer), from the side the
    // reference sees it from.
    const Eigen::Vector3d sc = view.camera.CamFromWorld(surface_world);
    if (!(sc.z() > 0)) continue;
    const Eigen::Vector2d sp = view.camera.ProjectCam(sc);
    if (!view.Inside(sp, r + 2)) continue;
    const float buffer = rasters[k].depth(int(std::lround(sp.y())), int(std::lround(sp.x())));
    if (!(sc.z() <= buffer * (1 + o.visibility_slack))) continue;
    if (n_world.dot(surface_world - view.camera.Center()) * ref_facing <= 0) continue;
    // Plane-induced homography of each depth: view_from_ref = R_rel + t_rel n^T / d.
    const Eigen::Matrix3d rel_r = view.camera.R * ref.camera.R.transpose();
    const Eigen::Vector3d rel_t = view.camera.t - rel_r * ref.camera.t;
    for (int s = 0; s < steps; ++s) {
      const Eigen::Vector3d X = ray * ((1.0 / inverse_depth(s)) / ray.z());
      const Eigen::Matrix3d H = view.camera.K * (rel_r + rel_t * n.transpose() / n.dot(X)) * k_inv;
      patch.clear();
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          const Eigen::Vector3d q = H * Eigen::Vector3d(u + dx, v + dy, 1);
          if (!(q.z() > 0)) break;
          const Eigen::Vector2d p(q.x() / q.z(), q.y() / q.z());
          if (!view.Inside(p, 0)) break;
          patch.push_back(SampleBilinear(view.grey, p.x(), p.y()));
        }
      if (patch.size() == ref_patch.size()) ncc[k][s] = Ncc(ref_patch, patch);
    }
  }
  // Each depth scores the mean of its two best photos.
  std::vector<double> score(steps), second(steps);
  for (int s = 0; s < steps; ++s) {
    double best = -1, next = -1;
    for (const std::vector<double>& photo : ncc) {
      if (photo[s] > best) {
        next = best;
        best = photo[s];
      } else if (photo[s] > next) {
        next = photo[s];
      }
    }
    score[s] = 0.5 * (best + next);
    second[s] = next;
  }
  const int peak = int(std::max_element(score.begin(), score.end()) - score.begin());
  if (second[peak] < o.min_ncc) return;
  for (int s = 0; s < steps; ++s)
    if (std::abs(s - peak) > o.unique_steps && score[s] > score[peak] - o.unique_margin) return;
  c->depth = 1.0 / inverse_depth(peak);
  c->found = true;
}

}  // namespace

void AddSweptPoints(const View& ref, const std::vector<View>& others, const cv::Mat1b& region,
                    const cv::Mat1b& page, const std::vector<Eigen::Vector3d>& known_points,
                    const cv::Mat& reference_bgr, const SweepOptions& o, DensifyResult* result) {
  std::vector<Eigen::Vector3d> known = known_points;
  const Eigen::Matrix3d k_inv = ref.camera.K.inverse();
  const double full_scale = double(reference_bgr.cols) / ref.grey.cols;
  for (int round = 0; round < o.rounds; ++round) {
    std::vector<Eigen::Vector3d> surface;
    std::vector<Triangle> triangles;
    PointsSurface(ref, region, known, o, &surface, &triangles);
    if (triangles.empty()) return;
    const RasterResult ref_raster = RasterizeMesh(ref.camera, surface, triangles);
    std::vector<RasterResult> rasters;
    for (const View& view : others)
      rasters.push_back(RasterizeMesh(view.camera, surface, triangles));

    std::vector<Candidate> candidates = Candidates(ref, page, known, ref_raster, o);
    result->sweep.candidates += int(candidates.size());
    cv::parallel_for_(cv::Range(0, int(candidates.size())), [&](const cv::Range& range) {
      for (int i = range.start; i < range.end; ++i)
        Sweep(ref, others, surface, triangles, ref_raster, rasters, o, &candidates[i]);
    });

    // A depth whose ratio to the surface differs from its found neighbours'
    // median is a stray match.
    std::vector<const Candidate*> found;
    for (const Candidate& c : candidates)
      if (c.found) found.push_back(&c);
    const double radius2 = o.neighbour_radius_px * o.neighbour_radius_px;
    int added = 0;
    for (const Candidate* c : found) {
      std::vector<double> ratios;
      for (const Candidate* other : found)
        if (other != c && (other->pixel - c->pixel).squaredNorm() <= radius2)
          ratios.push_back(other->depth / other->surface_depth);
      if (ratios.size() < 3) continue;
      const double median = NthSmallest(ratios, ratios.size() / 2);
      if (std::abs(c->depth / c->surface_depth - median) > o.max_ratio_deviation) continue;
      const Eigen::Vector3d ray = k_inv * Eigen::Vector3d(c->pixel.x(), c->pixel.y(), 1);
      const Eigen::Vector3d X =
          ref.camera.R.transpose() * (ray * (c->depth / ray.z()) - ref.camera.t);
      const Eigen::Vector2d full = ScalePixel(c->pixel, full_scale);
      const cv::Vec3b bgr = reference_bgr.at<cv::Vec3b>(
          std::clamp(int(std::lround(full.y())), 0, reference_bgr.rows - 1),
          std::clamp(int(std::lround(full.x())), 0, reference_bgr.cols - 1));
      // Three photos: the reference and the two best.
      AppendPoint(X, {bgr[2], bgr[1], bgr[0]}, 3, 0, PointSource::kSwept, &result->points);
      known.push_back(X);
      ++added;
    }
    result->sweep.points += added;
    if (added == 0) return;
  }
}

}  // namespace docunfold::densify::detail
