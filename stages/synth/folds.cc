#include "stages/synth/folds.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace docunfold::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;

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
  std::stable_sort(order_.begin(), order_.end(),
                   [&](int a, int b) { return far_area[a] > far_area[b]; });

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

std::vector<Fold> RandomFolds(double W, double H, const FoldOptions& options, std::mt19937* rng) {
  std::uniform_real_distribution<double> uni(0, 1);
  auto range = [&](double lo, double hi) { return lo + (hi - lo) * uni(*rng); };
  const Eigen::Vector2d centre(W / 2, H / 2);
  const int wanted = options.creases + (options.curl ? 1 : 0);
  if (wanted == 0) return {};

  for (int attempt = 0; attempt < 2000; ++attempt) {
    // A dominant direction: usually along a page side (a letter folded in
    // thirds), sometimes anything.
    double base = uni(*rng) < 0.6 ? (uni(*rng) < 0.5 ? 0.0 : kPi / 2) : range(0, kPi);
    base += range(-0.15, 0.15);
    std::vector<Fold> folds;
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segments;
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
        for (const Fold& f : folds) {
          Eigen::Vector2d n = Perp(f.direction);
          if (n.dot(centre - f.point) > 0) n = -n;
          if (n.dot(p - f.point) > 0) total += f.angle;
        }
        too_much = std::abs(total) * 180 / kPi > options.max_total_angle;
      }
    if (too_much) continue;
    return folds;
  }
  return {};  // the caller reports that no valid folds were found
}

}  // namespace docunfold::synth
