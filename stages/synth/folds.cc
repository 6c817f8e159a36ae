#include "stages/synth/folds.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "stages/synth/random.h"

namespace docunfold::synth {
namespace {

// Sampling of the self-intersection test (metres): fine enough for the arc of
// a 3 mm crease turned by 180 degrees (radius 1 mm) to keep its layers apart.
constexpr double kContactSpacing = 0.0015;

Eigen::Vector2d Perp(const Eigen::Vector2d& d) { return {-d.y(), d.x()}; }

// The part of line (p, d) inside the rectangle [0, W] x [0, H], as the
// parameter interval of p + s d; empty (lo > hi) when it misses.
std::pair<double, double> ClipToSheet(const Eigen::Vector2d& p, const Eigen::Vector2d& d, double W,
                                      double H) {
  double lo = -1e9, hi = 1e9;
  for (int k = 0; k < 2; ++k) {
    const double extent = k == 0 ? W : H;
    if (std::abs(d[k]) < 1e-12) {
      if (p[k] < 0 || p[k] > extent) return {1, 0};
      continue;
    }
    double a = (0 - p[k]) / d[k], b = (extent - p[k]) / d[k];
    if (a > b) std::swap(a, b);
    lo = std::max(lo, a);
    hi = std::min(hi, b);
  }
  return {lo, hi};
}

double SegmentDistance(const Eigen::Vector2d& a0, const Eigen::Vector2d& a1,
                       const Eigen::Vector2d& b0, const Eigen::Vector2d& b1) {
  auto point_seg = [](const Eigen::Vector2d& p, const Eigen::Vector2d& s0,
                      const Eigen::Vector2d& s1) {
    const Eigen::Vector2d d = s1 - s0;
    const double t = std::clamp((p - s0).dot(d) / std::max(d.squaredNorm(), 1e-18), 0.0, 1.0);
    return (s0 + t * d - p).norm();
  };
  // Crossing segments have distance 0.
  auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return u.x() * v.y() - u.y() * v.x();
  };
  const double d1 = cross(a1 - a0, b0 - a0), d2 = cross(a1 - a0, b1 - a0);
  const double d3 = cross(b1 - b0, a0 - b0), d4 = cross(b1 - b0, a1 - b0);
  if (d1 * d2 < 0 && d3 * d4 < 0) return 0;
  return std::min(
      {point_seg(a0, b0, b1), point_seg(a1, b0, b1), point_seg(b0, a0, a1), point_seg(b1, a0, a1)});
}

}  // namespace

FoldedSheet::FoldedSheet(double width_m, double height_m, std::vector<Fold> folds)
    : width_(width_m), height_(height_m), folds_(std::move(folds)) {
  const Eigen::Vector2d root(width_ / 2, height_ / 2);
  for (Fold& f : folds_) {
    f.direction.normalize();
    Eigen::Vector2d n = Perp(f.direction);
    if (n.dot(root - f.point) > 0) n = -n;
    normals_.push_back(n);
  }
  // Order from the root outwards: a fold nearer the root has a larger far
  // side (the far sides of non-crossing folds are nested or disjoint).
  std::vector<double> far_area(folds_.size(), 0);
  const int samples = 60;
  for (size_t i = 0; i < folds_.size(); ++i)
    for (int a = 0; a < samples; ++a)
      for (int b = 0; b < samples; ++b)
        if (Side(int(i), {(a + 0.5) / samples * width_, (b + 0.5) / samples * height_}) > 0)
          far_area[i] += 1;
  order_.resize(folds_.size());
  std::iota(order_.begin(), order_.end(), 0);
  // Narrow folds beside an end (an end curl's strips) can tie on the sampled
  // area; the one farther from the root is then the farther out.
  std::stable_sort(order_.begin(), order_.end(), [&](int a, int b) {
    if (far_area[a] != far_area[b]) return far_area[a] > far_area[b];
    return -Side(a, root) < -Side(b, root);
  });

  for (size_t i = 0; i < folds_.size(); ++i) {
    const Fold& f = folds_[i];
    const Eigen::Vector3d t(f.direction.x(), f.direction.y(), 0);
    const Eigen::Vector3d n(normals_[i].x(), normals_[i].y(), 0);
    const Eigen::Vector3d o(f.point.x(), f.point.y(), 0);
    const double a = std::abs(f.angle);
    const Eigen::Vector3d ez(0, 0, f.angle >= 0 ? 1.0 : -1.0);
    const double r = f.width / std::max(a, 1e-9);
    // Rotation about t that takes n to n cos a + ez sin a.
    const double psi = (f.angle >= 0 ? a : -a) * (t.cross(n).z() >= 0 ? 1.0 : -1.0);
    const Eigen::Vector3d c0 = o + n * (f.width / 2);
    const Eigen::Vector3d c1 =
        o - n * (f.width / 2) + n * r * std::sin(a) + ez * r * (1 - std::cos(a));
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(psi, t).toRotationMatrix();
    T.translation() = c1 - T.linear() * c0;
    far_side_.push_back(T);
  }
}

double FoldedSheet::Side(int i, const Eigen::Vector2d& uv) const {
  return normals_[i].dot(uv - folds_[i].point);
}

Eigen::Vector3d FoldedSheet::Map(const Eigen::Vector2d& uv) const {
  Eigen::Vector3d x(uv.x(), uv.y(), 0);
  // Farthest folds first: each fold moves everything beyond it, already
  // bent by the folds farther out, as one rigid piece.
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    const int i = *it;
    const Fold& f = folds_[i];
    const double d = Side(i, uv);
    if (d <= -f.width / 2) continue;
    if (d >= f.width / 2) {
      x = far_side_[i] * x;
      continue;
    }
    // Inside the strip: no fold farther out has touched this point, so it is
    // still flat; roll it onto the cylinder.
    const Eigen::Vector2d n2 = normals_[i];
    const Eigen::Vector3d n(n2.x(), n2.y(), 0);
    const Eigen::Vector3d ez(0, 0, f.angle >= 0 ? 1.0 : -1.0);
    const double a = std::abs(f.angle);
    const double r = f.width / std::max(a, 1e-9);
    const double s = d + f.width / 2;
    const Eigen::Vector2d start = uv - n2 * (d + f.width / 2);
    x = Eigen::Vector3d(start.x(), start.y(), 0) + n * r * std::sin(s / r) +
        ez * r * (1 - std::cos(s / r));
  }
  return x;
}

std::vector<Fold> RandomFolds(double W, double H, const FoldOptions& options, std::mt19937* rng,
                              const std::vector<Fold>& fixed) {
  std::uniform_real_distribution<double> uni(0, 1);
  auto range = [&](double lo, double hi) { return lo + (hi - lo) * uni(*rng); };
  const Eigen::Vector2d centre(W / 2, H / 2);
  const int wanted = options.creases + (options.curl ? 1 : 0);
  // Up to max_total_angle no path turns far enough for the sheet to meet
  // itself; beyond it (a flap, a steep panel) only a test of the folded
  // sheet can tell.
  const bool check_contact = !fixed.empty() || options.crease_angle_max > options.max_total_angle;
  const double max_total = std::max(options.max_total_angle, options.crease_angle_max);
  if (wanted == 0) {
    if (fixed.empty()) return {};
    return SelfIntersects(FoldedSheet(W, H, fixed), kContactSpacing) ? std::vector<Fold>{} : fixed;
  }
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> fixed_segments;
  for (const Fold& f : fixed) {
    const auto [lo, hi] = ClipToSheet(f.point, f.direction, W, H);
    fixed_segments.emplace_back(f.point + lo * f.direction, f.point + hi * f.direction);
  }

  for (int attempt = 0; attempt < 2000; ++attempt) {
    // A dominant direction: usually along a page side (a letter folded in
    // thirds), sometimes anything.
    double base = uni(*rng) < 0.6 ? (uni(*rng) < 0.5 ? 0.0 : kPi / 2) : range(0, kPi);
    base += range(-0.15, 0.15);
    std::vector<Fold> folds = fixed;
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segments = fixed_segments;
    bool ok = true;
    for (int k = 0; k < wanted && ok; ++k) {
      const bool is_curl = options.curl && k == wanted - 1;
      Fold f;
      const double dir_angle = base + range(-0.35, 0.35);
      f.direction = {std::cos(dir_angle), std::sin(dir_angle)};
      const Eigen::Vector2d n = Perp(f.direction);
      // Extent of the sheet along n, seen from the centre.
      double extent = 0;
      for (const Eigen::Vector2d& c : {Eigen::Vector2d(0, 0), Eigen::Vector2d(W, 0),
                                       Eigen::Vector2d(0, H), Eigen::Vector2d(W, H)})
        extent = std::max(extent, std::abs(n.dot(c - centre)));
      const double offset =
          (uni(*rng) < 0.5 ? -1 : 1) * (is_curl ? range(0.45, 0.7) : range(0.1, 0.6)) * extent;
      f.point = centre + n * offset;
      f.width = is_curl ? range(options.curl_width_min, options.curl_width_max)
                        : range(options.crease_width_min,
                                std::max(options.crease_width_min, options.crease_width_max));
      const double deg = is_curl ? range(options.curl_angle_min, options.curl_angle_max)
                                 : range(options.crease_angle_min, options.crease_angle_max);
      f.angle = deg * kPi / 180 * (uni(*rng) < 0.5 ? -1 : 1);
      // The line must cross the sheet well away from the corners, keep the
      // centre (the root panel) off its strip, and keep its strip clear of
      // every other fold's.
      auto [lo, hi] = ClipToSheet(f.point, f.direction, W, H);
      if (hi - lo < 0.3 * std::min(W, H)) {
        ok = false;
        break;
      }
      const Eigen::Vector2d a = f.point + lo * f.direction, b = f.point + hi * f.direction;
      for (const Eigen::Vector2d& c : {Eigen::Vector2d(0, 0), Eigen::Vector2d(W, 0),
                                       Eigen::Vector2d(0, H), Eigen::Vector2d(W, H)})
        if ((a - c).norm() < 0.03 || (b - c).norm() < 0.03) ok = false;
      if (std::abs(n.dot(centre - f.point)) < f.width / 2 + 0.01) ok = false;
      for (size_t j = 0; j < folds.size() && ok; ++j)
        if (SegmentDistance(a, b, segments[j].first, segments[j].second) <
            (f.width + folds[j].width) / 2 + 0.012)
          ok = false;
      folds.push_back(f);
      segments.emplace_back(a, b);
    }
    if (!ok) continue;
    // No panel may turn by more than max_total_angle relative to the root,
    // or the sheet would fold through itself.
    FoldedSheet sheet(W, H, folds);
    bool too_much = false;
    for (int a = 0; a < 24 && !too_much; ++a)
      for (int b = 0; b < 24 && !too_much; ++b) {
        const Eigen::Vector2d p((a + 0.5) / 24 * W, (b + 0.5) / 24 * H);
        double total = 0;
        for (size_t k = fixed.size(); k < folds.size(); ++k) {
          const Fold& f = folds[k];
          Eigen::Vector2d n = Perp(f.direction);
          if (n.dot(centre - f.point) > 0) n = -n;
          if (n.dot(p - f.point) > 0) total += f.angle;
        }
        too_much = std::abs(total) * 180 / kPi > max_total;
      }
    if (too_much) continue;
    if (check_contact && SelfIntersects(sheet, kContactSpacing)) continue;
    return folds;
  }
  return {};  // the caller reports that no valid folds were found
}

namespace {

// Whether segment a-b crosses triangle p0 p1 p2 (Moller-Trumbore); a segment
// in the triangle's plane does not count (flat panels are coplanar with
// themselves).
bool SegmentCrosses(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& p0,
                    const Eigen::Vector3d& p1, const Eigen::Vector3d& p2) {
  const Eigen::Vector3d d = b - a, e1 = p1 - p0, e2 = p2 - p0;
  const Eigen::Vector3d h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) <= 1e-9 * d.norm() * e1.norm() * e2.norm()) return false;
  const Eigen::Vector3d s = a - p0;
  const double u = s.dot(h) / det;
  if (u < 0 || u > 1) return false;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) / det;
  if (v < 0 || u + v > 1) return false;
  const double t = e2.dot(q) / det;
  return t > 0 && t < 1;
}

}  // namespace

bool SelfIntersects(const FoldedSheet& sheet, double spacing) {
  const int nx = std::max(2, int(std::ceil(sheet.width() / spacing)) + 1);
  const int ny = std::max(2, int(std::ceil(sheet.height() / spacing)) + 1);
  std::vector<Eigen::Vector3d> p;
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c)
      p.push_back(sheet.Map({sheet.width() * c / (nx - 1), sheet.height() * r / (ny - 1)}));
  std::vector<std::array<int, 3>> triangles;
  for (int r = 0; r + 1 < ny; ++r)
    for (int c = 0; c + 1 < nx; ++c) {
      const int a = r * nx + c, b = a + 1, d = a + nx, e = d + 1;
      triangles.push_back({a, b, e});
      triangles.push_back({a, e, d});
    }
  // Triangles binned by their bounding boxes in a uniform grid of cells.
  Eigen::Vector3d lo = p[0];
  for (const Eigen::Vector3d& x : p) lo = lo.cwiseMin(x);
  const double cell = 2 * spacing;
  auto index = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3i(int((x.x() - lo.x()) / cell), int((x.y() - lo.y()) / cell),
                           int((x.z() - lo.z()) / cell));
  };
  auto key = [](int i, int j, int k) {
    return (int64_t(i) << 42) | (int64_t(j) << 21) | int64_t(k);
  };
  auto for_cells = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       auto&& visit) {
    const Eigen::Vector3i i0 = index(a.cwiseMin(b).cwiseMin(c)),
                          i1 = index(a.cwiseMax(b).cwiseMax(c));
    for (int i = i0.x(); i <= i1.x(); ++i)
      for (int j = i0.y(); j <= i1.y(); ++j)
        for (int k = i0.z(); k <= i1.z(); ++k) visit(key(i, j, k));
  };
  std::unordered_map<int64_t, std::vector<int>> bins;
  for (size_t t = 0; t < triangles.size(); ++t) {
    const auto& T = triangles[t];
    for_cells(p[T[0]], p[T[1]], p[T[2]], [&](int64_t k) { bins[k].push_back(int(t)); });
  }
  // Every edge against the triangles near it that share none of its ends.
  for (const auto& T : triangles)
    for (int e = 0; e < 3; ++e) {
      const int i = T[e], j = T[(e + 1) % 3];
      bool crossing = false;
      for_cells(p[i], p[j], p[j], [&](int64_t k) {
        auto it = bins.find(k);
        if (crossing || it == bins.end()) return;
        for (int t : it->second) {
          const auto& U = triangles[t];
          if (U[0] == i || U[1] == i || U[2] == i || U[0] == j || U[1] == j || U[2] == j) continue;
          if (SegmentCrosses(p[i], p[j], p[U[0]], p[U[1]], p[U[2]])) {
            crossing = true;
            return;
          }
        }
      });
      if (crossing) return true;
    }
  return false;
}

std::vector<Fold> ShapeFolds(double W, double H, const ShapeOptions& shapes,
                             const FoldOptions& folds, std::mt19937* rng) {
  std::vector<Fold> out;
  if (!shapes.any()) return out;
  std::uniform_real_distribution<double> uni(0, 1);
  auto range = [&](double lo, double hi) { return lo + (hi - lo) * uni(*rng); };
  auto crease_width = [&] {
    return range(folds.crease_width_min, std::max(folds.crease_width_min, folds.crease_width_max));
  };
  const bool curl_top = shapes.end_curl == PageEnd::kTop || shapes.end_curl == PageEnd::kBoth;
  const bool curl_bottom = shapes.end_curl == PageEnd::kBottom || shapes.end_curl == PageEnd::kBoth;
  bool free_end[2] = {!curl_top, !curl_bottom};  // top, bottom
  // Each shape needs an end of its own, or their strips would cross.
  auto take_end = [&](const char* what) {
    if (!free_end[0] && !free_end[1])
      throw std::invalid_argument(std::string(what) + " needs an end of the page that " +
                                  "no other shape uses");
    const int e = free_end[0] && free_end[1] ? (uni(*rng) < 0.5 ? 0 : 1) : (free_end[0] ? 0 : 1);
    free_end[e] = false;
    return e;
  };
  // A fold across the page at `distance` from end e (0 top, 1 bottom),
  // turned by `tilt` radians; its far side is the end.
  auto across = [&](int e, double distance, double tilt, double width, double angle_deg) {
    Fold f;
    f.point = {W / 2, e == 0 ? distance : H - distance};
    f.direction = {std::cos(tilt), std::sin(tilt)};
    f.width = width;
    f.angle = kTowardsPrint * angle_deg * kPi / 180;
    return f;
  };
  // An end curl: adjacent strips up to the edge, each bent more than the one
  // before, so that the curvature grows towards the end as a roll's does.
  const int strips = 6;
  const double length = std::min(shapes.end_curl_length, 0.4 * H);
  for (int e = 0; e < 2; ++e) {
    if (!(e == 0 ? curl_top : curl_bottom)) continue;
    for (int i = 0; i < strips; ++i)
      out.push_back(across(e, length * (1 - (i + 0.5) / strips), 0, length / strips,
                           shapes.end_curl_angle * (i + 1) / (strips * (strips + 1) / 2)));
  }
  if (shapes.steep_angle > 0) {
    const int e = take_end("--steep-fold");
    out.push_back(
        across(e, range(0.18, 0.3) * H, range(-0.08, 0.08), crease_width(), shapes.steep_angle));
  }
  if (shapes.flap == Flap::kEnd) {
    const int e = take_end("--flap end");
    out.push_back(
        across(e, range(0.1, 0.2) * H, range(-0.1, 0.1), crease_width(), shapes.flap_angle));
  } else if (shapes.flap == Flap::kCorner) {
    const int e = take_end("--flap corner");
    const bool left = uni(*rng) < 0.5;
    const double a = range(0.3, 0.55) * W;
    const double b = std::min(a * range(0.8, 1.25), 0.4 * H);
    const Eigen::Vector2d corner(left ? 0 : W, e == 0 ? 0 : H);
    const Eigen::Vector2d p1 = corner + Eigen::Vector2d(left ? a : -a, 0);
    const Eigen::Vector2d p2 = corner + Eigen::Vector2d(0, e == 0 ? b : -b);
    Fold f;
    f.point = (p1 + p2) / 2;
    f.direction = (p2 - p1).normalized();
    f.width = crease_width();
    f.angle = kTowardsPrint * shapes.flap_angle * kPi / 180;
    out.push_back(f);
  }
  return out;
}

}  // namespace docunfold::synth
