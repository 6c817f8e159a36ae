#include "stages/init-mesh/outline_prior.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "common/point_index.h"
#include "common/raster.h"
#include "common/statistics.h"

namespace docunfold::init_mesh {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Distance from `p` to a polyline and the arc-length fraction (0..1) of the
// nearest point on it.
std::pair<double, double> OnPolyline(const Eigen::Vector2d& p,
                                     const std::vector<Eigen::Vector2d>& poly) {
  double total = 0;
  for (size_t k = 1; k < poly.size(); ++k) total += (poly[k] - poly[k - 1]).norm();
  double best = std::numeric_limits<double>::infinity(), best_t = 0, walked = 0;
  for (size_t k = 1; k < poly.size(); ++k) {
    const Eigen::Vector2d a = poly[k - 1], d = poly[k] - poly[k - 1];
    const double len2 = d.squaredNorm();
    const double s = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double dist = (a + s * d - p).norm();
    if (dist < best) {
      best = dist;
      best_t = total > 0 ? (walked + s * std::sqrt(len2)) / total : 0;
    }
    walked += std::sqrt(len2);
  }
  return {best, best_t};
}

// Inverse depth along a side, from its outline points sorted by position.
struct Profile {
  std::vector<double> t, inverse_depth;
  bool Usable(int min_points) const { return int(t.size()) >= min_points; }
  double At(double x) const {
    if (x <= t.front()) return inverse_depth.front();
    if (x >= t.back()) return inverse_depth.back();
    const size_t k = size_t(std::upper_bound(t.begin(), t.end(), x) - t.begin());
    const double f = (x - t[k - 1]) / std::max(t[k] - t[k - 1], 1e-12);
    return (1 - f) * inverse_depth[k - 1] + f * inverse_depth[k];
  }
};

// A running median over 5 samples: a stray outline point does not kink the
// side.
void SmoothProfile(Profile* p) {
  const size_t n = p->inverse_depth.size();
  if (n < 5) return;
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t lo = i < 2 ? 0 : i - 2, hi = std::min(n, i + 3);
    out[i] = Median(std::vector<double>(p->inverse_depth.begin() + long(lo),
                                        p->inverse_depth.begin() + long(hi)));
  }
  p->inverse_depth = std::move(out);
}

// Fills the NaN entries of a border line of the grid by interpolating the
// inverse depth linearly in image arc length (exact for a straight 3D edge,
// whose inverse depth is affine along its image). False when none is known.
bool FillBorderLine(const std::vector<Eigen::Vector2d>& pixels,
                    std::vector<double>* inverse_depth) {
  const size_t n = pixels.size();
  std::vector<double> s(n, 0);
  for (size_t i = 1; i < n; ++i) s[i] = s[i - 1] + (pixels[i] - pixels[i - 1]).norm();
  std::vector<size_t> known;
  for (size_t i = 0; i < n; ++i)
    if (std::isfinite((*inverse_depth)[i])) known.push_back(i);
  if (known.empty()) return false;
  for (size_t i = 0; i < n; ++i) {
    if (std::isfinite((*inverse_depth)[i])) continue;
    const auto after = std::upper_bound(known.begin(), known.end(), i);
    if (after == known.begin()) {
      (*inverse_depth)[i] = (*inverse_depth)[known.front()];
    } else if (after == known.end()) {
      (*inverse_depth)[i] = (*inverse_depth)[known.back()];
    } else {
      const size_t a = *(after - 1), b = *after;
      const double f = (s[i] - s[a]) / std::max(s[b] - s[a], 1e-12);
      (*inverse_depth)[i] = (1 - f) * (*inverse_depth)[a] + f * (*inverse_depth)[b];
    }
  }
  return true;
}

// 1. The real sides' inverse depth along them, from the outline points
// (each on the nearest real side within side_distance_px), sorted along the
// side and smoothed; counted into r->side_points and r->measured_sides.
std::array<Profile, 4> SideProfiles(const std::array<std::vector<Eigen::Vector2d>, 4>& sides,
                                    const std::array<bool, 4>& real,
                                    const std::vector<Eigen::Vector2d>& outline_pixels,
                                    const std::vector<double>& outline_depths,
                                    const OutlinePriorOptions& o, OutlinePriorResult* r) {
  std::array<Profile, 4> profiles;
  for (size_t i = 0; i < outline_pixels.size(); ++i) {
    int side = -1;
    double nearest = o.side_distance_px, t = 0;
    for (int s = 0; s < 4; ++s) {
      if (!real[s] || sides[s].size() < 2) continue;
      const auto [d, ts] = OnPolyline(outline_pixels[i], sides[s]);
      if (d <= nearest) {
        nearest = d;
        side = s;
        t = ts;
      }
    }
    if (side < 0 || !(outline_depths[i] > 0)) continue;
    profiles[side].t.push_back(t);
    profiles[side].inverse_depth.push_back(1 / outline_depths[i]);
  }
  for (int s = 0; s < 4; ++s) {
    Profile& p = profiles[s];
    std::vector<size_t> order(p.t.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return p.t[a] < p.t[b]; });
    Profile sorted;
    for (size_t k : order) {
      sorted.t.push_back(p.t[k]);
      sorted.inverse_depth.push_back(p.inverse_depth[k]);
    }
    SmoothProfile(&sorted);
    p = std::move(sorted);
    r->side_points[s] = int(p.t.size());
    r->measured_sides += p.Usable(o.min_side_points);
  }
  return profiles;
}

// 2. The grid's border vertices at the inverse depth of the side they lie
// on; a side without its own points straight between its corners. False
// (and why in `note`) when a border line gets no depth.
bool BorderInverseDepths(const QuadGrid& grid, const std::vector<Eigen::Vector2d>& grid_pixels,
                         const std::array<std::vector<Eigen::Vector2d>, 4>& sides,
                         const std::array<Profile, 4>& profiles, const OutlinePriorOptions& o,
                         std::vector<double>* border_out, std::string* note) {
  const int nx = grid.nx, ny = grid.ny;
  std::vector<double> border(size_t(nx) * ny, kNaN);
  auto border_vertex = [&](int row, int col) {
    const Eigen::Vector2d& p = grid_pixels[size_t(grid.Index(row, col))];
    int side = -1;
    double nearest = std::numeric_limits<double>::infinity(), t = 0;
    for (int s = 0; s < 4; ++s) {
      if (sides[s].size() < 2) continue;
      const auto [d, ts] = OnPolyline(p, sides[s]);
      if (d < nearest) {
        nearest = d;
        side = s;
        t = ts;
      }
    }
    if (side >= 0 && profiles[side].Usable(o.min_side_points))
      border[size_t(grid.Index(row, col))] = profiles[side].At(t);
  };
  for (int c = 0; c < nx; ++c) {
    border_vertex(0, c);
    border_vertex(ny - 1, c);
  }
  for (int row = 0; row < ny; ++row) {
    border_vertex(row, 0);
    border_vertex(row, nx - 1);
  }
  // The four border lines, each filled along itself (corners first shared).
  std::array<std::vector<int>, 4> lines;
  for (int c = 0; c < nx; ++c) {
    lines[0].push_back(grid.Index(0, c));
    lines[2].push_back(grid.Index(ny - 1, c));
  }
  for (int row = 0; row < ny; ++row) {
    lines[1].push_back(grid.Index(row, nx - 1));
    lines[3].push_back(grid.Index(row, 0));
  }
  // A line without points of its own (no outline point on its side) gets
  // its corners from the crossing lines, so the rows go again once the
  // columns are done: which side that is depends only on how the grid lies
  // on the page (see docs/decisions/init-mesh.md, "The outline prior").
  for (int pass = 0; pass < 2; ++pass)
    for (const auto& line : lines) {
      std::vector<Eigen::Vector2d> px;
      std::vector<double> w;
      for (int v : line) {
        px.push_back(grid_pixels[size_t(v)]);
        w.push_back(border[size_t(v)]);
      }
      if (!FillBorderLine(px, &w)) continue;  // maybe filled from a crossing line
      for (size_t k = 0; k < line.size(); ++k) border[size_t(line[k])] = w[k];
    }
  for (const auto& line : lines)
    for (int v : line)
      if (!(border[size_t(v)] > 0)) {
        *note = "a border of the grid has no depth from the outline";
        return false;
      }
  *border_out = std::move(border);
  return true;
}

// 3. The Coons patch of the four border curves in 3D (camera frame): the
// inverse depth it gives each grid vertex. False (and why in `note`) when it
// passes behind the camera.
bool PatchInverseDepths(const QuadGrid& grid, const std::vector<Eigen::Vector2d>& grid_pixels,
                        const std::vector<double>& border, const PinholeCamera& camera,
                        std::vector<double>* prior_out, std::string* note) {
  const int nx = grid.nx, ny = grid.ny;
  auto on_ray = [&](int v) -> Eigen::Vector3d {
    return camera.CamRay(grid_pixels[size_t(v)]) / border[size_t(v)];
  };
  std::vector<double> prior(size_t(nx) * ny, kNaN);  // inverse depth
  const Eigen::Vector3d c00 = on_ray(grid.Index(0, 0)), c01 = on_ray(grid.Index(0, nx - 1)),
                        c10 = on_ray(grid.Index(ny - 1, 0)),
                        c11 = on_ray(grid.Index(ny - 1, nx - 1));
  for (int row = 0; row < ny; ++row)
    for (int col = 0; col < nx; ++col) {
      const double u = double(col) / (nx - 1), v = double(row) / (ny - 1);
      const Eigen::Vector3d x =
          (1 - v) * on_ray(grid.Index(0, col)) + v * on_ray(grid.Index(ny - 1, col)) +
          (1 - u) * on_ray(grid.Index(row, 0)) + u * on_ray(grid.Index(row, nx - 1)) -
          ((1 - u) * (1 - v) * c00 + u * (1 - v) * c01 + (1 - u) * v * c10 + u * v * c11);
      if (x.z() > 0) prior[size_t(grid.Index(row, col))] = 1 / x.z();
    }
  for (double w : prior)
    if (!(w > 0)) {
      *note = "the outline's patch passes behind the camera";
      return false;
    }
  *prior_out = std::move(prior);
  return true;
}

// The points judged against the patch: their pixels, their inverse depth
// minus the patch's, and that residual relative to their depth.
struct Residuals {
  std::vector<Eigen::Vector2d> pixels;
  std::vector<double> residual, relative;
};

// 4. The points' residuals against the patch (`prior`, inverse depth per
// grid vertex): its inverse depth at their pixels from a raster of the
// image grid.
Residuals PointResiduals(const QuadGrid& grid, const std::vector<Eigen::Vector2d>& grid_pixels,
                         const std::vector<double>& grid_depths, const std::vector<double>& prior,
                         const PinholeCamera& camera,
                         const std::vector<Eigen::Vector2d>& point_pixels,
                         const std::vector<double>& point_depths) {
  const double scale = std::min(1.0, 1600.0 / std::max(camera.width, camera.height));
  std::vector<Eigen::Vector3d> screen;
  for (size_t v = 0; v < grid_pixels.size(); ++v)
    screen.emplace_back(grid_pixels[v].x() * scale, grid_pixels[v].y() * scale,
                        std::max(grid_depths[v], 1e-6));
  const std::vector<Triangle> triangles = grid.Triangles();
  const RasterResult raster = Rasterize(screen, triangles, int(std::ceil(camera.width * scale)),
                                        int(std::ceil(camera.height * scale)));
  Eigen::MatrixXf attribute(prior.size(), 1);
  for (size_t v = 0; v < prior.size(); ++v) attribute(long(v), 0) = float(prior[v]);
  const cv::Mat prior_image = InterpolateAttributes(raster, triangles, attribute);
  Residuals judged;
  for (size_t i = 0; i < point_pixels.size(); ++i) {
    const int x = int(std::lround(point_pixels[i].x() * scale)),
              y = int(std::lround(point_pixels[i].y() * scale));
    if (x < 0 || y < 0 || x >= prior_image.cols || y >= prior_image.rows) continue;
    const float w = prior_image.at<float>(y, x);
    if (!std::isfinite(w) || !(point_depths[i] > 0)) continue;
    judged.pixels.push_back(point_pixels[i]);
    judged.residual.push_back(1 / point_depths[i] - w);
    judged.relative.push_back(judged.residual.back() * point_depths[i]);
  }
  return judged;
}

// 5. Per grid vertex: the patch corrected by the points near it, weighed
// against the points' own planar depth by how well the patch fits them.
// Fills r->depth and r->mean_weight.
void BlendWithPoints(const std::vector<Eigen::Vector2d>& grid_pixels,
                     const std::vector<double>& grid_depths, const std::vector<double>& prior,
                     const Residuals& judged, const PinholeCamera& camera,
                     const OutlinePriorOptions& o, OutlinePriorResult* r) {
  const double diagonal = std::hypot(camera.width, camera.height);
  const PointIndex2d index(judged.pixels);
  const double radius = o.radius_fraction * diagonal;
  r->depth.resize(prior.size());
  double weight_sum = 0;
  for (size_t v = 0; v < prior.size(); ++v) {
    double sw = 0, swr = 0, swe = 0;
    for (const auto& [i, d2] : index.Nearest(grid_pixels[v], o.neighbours)) {
      const double w = 1 / (1 + d2 / (radius * radius));
      sw += w;
      swr += w * judged.residual[size_t(i)];
      swe += w * judged.relative[size_t(i)] * judged.relative[size_t(i)];
    }
    const double correction = swr / (o.prior_weight + sw);
    const double rms = sw > 0 ? std::sqrt(swe / sw) : 0;
    const double alpha = std::exp(-(rms * rms) / (o.agreement * o.agreement));
    const double inverse =
        alpha * (prior[v] + correction) + (1 - alpha) / std::max(grid_depths[v], 1e-9);
    r->depth[v] = inverse > 0 ? 1 / inverse : grid_depths[v];
    weight_sum += alpha;
  }
  r->mean_weight = weight_sum / double(prior.size());
}

}  // namespace

OutlinePriorResult OutlinePriorDepths(
    const QuadGrid& grid, const std::vector<Eigen::Vector2d>& grid_pixels,
    const std::vector<double>& grid_depths,
    const std::array<std::vector<Eigen::Vector2d>, 4>& sides, const std::array<bool, 4>& real,
    const PinholeCamera& camera, const std::vector<Eigen::Vector2d>& outline_pixels,
    const std::vector<double>& outline_depths, const std::vector<Eigen::Vector2d>& point_pixels,
    const std::vector<double>& point_depths, const OutlinePriorOptions& o) {
  OutlinePriorResult r;
  const int nx = grid.nx, ny = grid.ny;
  if (!o.enabled) {
    r.note = "off";
    return r;
  }
  if (nx < 2 || ny < 2 || int(grid_pixels.size()) != nx * ny) {
    r.note = "no grid";
    return r;
  }
  const std::array<Profile, 4> profiles =
      SideProfiles(sides, real, outline_pixels, outline_depths, o, &r);
  if (r.measured_sides < o.min_measured_sides) {
    r.note = std::to_string(r.measured_sides) + " sides with outline points (" +
             std::to_string(o.min_measured_sides) + " needed)";
    return r;
  }
  std::vector<double> border, prior;
  if (!BorderInverseDepths(grid, grid_pixels, sides, profiles, o, &border, &r.note)) return r;
  if (!PatchInverseDepths(grid, grid_pixels, border, camera, &prior, &r.note)) return r;
  const Residuals judged =
      PointResiduals(grid, grid_pixels, grid_depths, prior, camera, point_pixels, point_depths);
  if (judged.pixels.empty()) {
    r.note = "no point on the grid";
    return r;
  }
  BlendWithPoints(grid_pixels, grid_depths, prior, judged, camera, o, &r);
  r.used = true;
  return r;
}

}  // namespace docunfold::init_mesh
