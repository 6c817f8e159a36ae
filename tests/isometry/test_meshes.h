// Mesh pairs for the isometry and init-mesh tests: exactly developable
// analytic sheets, and the ground truth of a data set as a MeshPair (full or
// on a coarser sub-grid), plus distances to a true surface.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "common/grid_mesh.h"
#include "common/isometry/mesh_index.h"
#include "tests/support/ground_truth.h"
#include "tests/support/test_support.h"
#include "tests/support/truth_frame.h"

namespace docunfold::testing {

// A w x h sheet on an nx x ny vertex grid, bent along its columns: the
// direction of the profile turns by `turn(c)` radians at column c. Each quad
// stays a planar rectangle, so the pair is exactly isometric. It sits around
// z = 1 in front of an identity camera, x right, y down.
template <class Turn>
MeshPair ProfileSheet(int nx, int ny, double w, double h, Turn turn) {
  MeshPair m;
  m.grid = {nx, ny};
  const double dx = w / (nx - 1), dy = h / (ny - 1);
  std::vector<Eigen::Vector2d> profile(nx);  // (x, z)
  double angle = 0;
  profile[0] = {0, 0};
  for (int c = 1; c < nx; ++c) {
    angle += turn(c - 1);
    profile[c] = profile[c - 1] + dx * Eigen::Vector2d(std::cos(angle), std::sin(angle));
  }
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : profile) mean += p / nx;
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      m.mesh3d.emplace_back(profile[c].x() - mean.x(), r * dy - h / 2,
                            1.0 + profile[c].y() - mean.y());
      m.mesh2d.emplace_back(c * dx, r * dy);
    }
  return m;
}

// A sheet curled around a cylinder of the given radius (total turn w/R),
// polygonal along the columns, exactly isometric.
inline MeshPair CurledSheet(int nx, int ny, double w, double h, double radius) {
  const double dx = w / (nx - 1);
  const double step = 2 * std::asin(std::min(1.0, dx / (2 * radius)));
  return ProfileSheet(nx, ny, w, h, [&](int c) { return c == 0 ? -step * (nx - 2) / 2 : step; });
}

// The pair of a data set's ground truth in the reference frame.
inline MeshPair TrueMeshPair(const GroundTruth& gt, const std::string& reference) {
  const TrueMeshes t = TrueMeshesInReferenceFrame(gt, reference);
  MeshPair m;
  auto size = t.mesh3d.GridSize();
  m.grid = {(*size)[0], (*size)[1]};
  m.mesh3d = t.mesh3d.vertices;
  for (const auto& v : t.mesh2d.vertices) m.mesh2d.push_back(v.head<2>());
  return m;
}

// Every `step`-th row and column of a pair (the last ones always kept).
inline MeshPair SubGrid(const MeshPair& m, int step) {
  std::vector<int> rows, cols;
  for (int r = 0; r < m.grid.ny; r += step) rows.push_back(r);
  if (rows.back() != m.grid.ny - 1) rows.push_back(m.grid.ny - 1);
  for (int c = 0; c < m.grid.nx; c += step) cols.push_back(c);
  if (cols.back() != m.grid.nx - 1) cols.push_back(m.grid.nx - 1);
  MeshPair s;
  s.grid = {int(cols.size()), int(rows.size())};
  for (int r : rows)
    for (int c : cols) {
      s.mesh3d.push_back(m.mesh3d[m.grid.Index(r, c)]);
      s.mesh2d.push_back(m.mesh2d[m.grid.Index(r, c)]);
    }
  return s;
}

// The pair resampled on an nx x ny grid by bilinear interpolation in the
// grid parameters of `m` (M' stays exact for a regular flat grid).
inline MeshPair Resample(const MeshPair& m, int nx, int ny) {
  MeshPair s;
  s.grid = {nx, ny};
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      const double u = double(c) / (nx - 1) * (m.grid.nx - 1);
      const double v = double(r) / (ny - 1) * (m.grid.ny - 1);
      const int c0 = std::min(int(u), m.grid.nx - 2), r0 = std::min(int(v), m.grid.ny - 2);
      const double fu = u - c0, fv = v - r0;
      auto mix = [&](const auto& field) {
        return (1 - fv) *
                   ((1 - fu) * field[m.grid.Index(r0, c0)] + fu * field[m.grid.Index(r0, c0 + 1)]) +
               fv * ((1 - fu) * field[m.grid.Index(r0 + 1, c0)] +
                     fu * field[m.grid.Index(r0 + 1, c0 + 1)]);
      };
      s.mesh3d.push_back(mix(m.mesh3d));
      s.mesh2d.push_back(mix(m.mesh2d));
    }
  return s;
}

// Distances from samples of `from` (vertices and quad centres) to the
// triangulated surface `to`.
struct DistanceStats {
  double mean = 0;
  double max = 0;
  double p99 = 0;  // 99th percentile: all but the farthest 1 % of the samples
};
inline DistanceStats SurfaceDistance(const MeshPair& from, const MeshPair& to) {
  isometry::TriangleMeshIndex index(to.mesh3d, to.grid.Triangles());
  std::vector<Eigen::Vector3d> samples = from.mesh3d;
  for (int q = 0; q < from.grid.NumQuads(); ++q) {
    const auto c = from.grid.Quad(q);
    samples.push_back(
        (from.mesh3d[c[0]] + from.mesh3d[c[1]] + from.mesh3d[c[2]] + from.mesh3d[c[3]]) / 4);
  }
  DistanceStats s;
  std::vector<double> distances;
  for (const auto& p : samples) {
    const double d = index.Closest(p)->distance;
    distances.push_back(d);
    s.mean += d / samples.size();
    s.max = std::max(s.max, d);
  }
  if (distances.empty()) return s;
  const auto at = distances.begin() + (distances.size() * 99) / 100;
  std::nth_element(distances.begin(), at, distances.end());
  s.p99 = *at;
  return s;
}

// Every data set with ground truth (samples/*, ../shared/realistic/*).
inline std::vector<fs::path> DataSetsWithGroundTruth() {
  std::vector<fs::path> sets;
  for (const fs::path& base : {SourceDir() / "samples", RealisticDir()}) {
    std::error_code ec;
    if (base.empty() || !fs::is_directory(base, ec)) continue;
    for (const auto& e : fs::directory_iterator(base))
      if (fs::is_regular_file(e.path() / "ground_truth" / "mesh.ply", ec) &&
          fs::is_regular_file(e.path() / "ground_truth" / "cameras.json", ec))
        sets.push_back(e.path());
  }
  std::sort(sets.begin(), sets.end());
  return sets;
}

// The view a good sfm would choose as reference: the whole page inside the
// image and the largest page area.
inline std::string ChooseReferenceView(const GroundTruth& gt) {
  std::string best;
  double best_area = -1;
  for (const PinholeCamera& cam : gt.cameras.views) {
    bool inside = true;
    for (const Eigen::Vector2d& c : TrueCorners(gt, cam))
      inside =
          inside && c.x() >= 2 && c.y() >= 2 && c.x() <= cam.width - 3 && c.y() <= cam.height - 3;
    const double area = cv::countNonZero(TruePageMask(gt, cam)) * (inside ? 1.0 : 1e-3);
    if (area > best_area) {
      best_area = area;
      best = cam.image;
    }
  }
  return best;
}

// Points on the surface of a pair's M (uniform over its triangles' area),
// with Gaussian noise (sigma, absolute) and appended outliers uniform in the
// bounding box; outlier[i] tells which are which.
struct SampledPoints {
  std::vector<Eigen::Vector3d> points;
  std::vector<bool> outlier;
};
inline SampledPoints SampleSurface(const MeshPair& m, int count, double sigma,
                                   double outlier_fraction, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0, 1);
  std::normal_distribution<double> gauss(0, 1);
  const auto tris = m.grid.Triangles();
  std::vector<double> cumulative;
  double total = 0;
  for (const Triangle& t : tris) {
    total += 0.5 * (m.mesh3d[t[1]] - m.mesh3d[t[0]]).cross(m.mesh3d[t[2]] - m.mesh3d[t[0]]).norm();
    cumulative.push_back(total);
  }
  SampledPoints s;
  Eigen::Vector3d lo = m.mesh3d[0], hi = lo;
  for (const auto& v : m.mesh3d) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  for (int i = 0; i < count; ++i) {
    const double pick = uni(rng) * total;
    const size_t t = std::min(
        tris.size() - 1,
        size_t(std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin()));
    double a = uni(rng), b = uni(rng);
    if (a + b > 1) {
      a = 1 - a;
      b = 1 - b;
    }
    const Triangle& tri = tris[t];
    Eigen::Vector3d p =
        (1 - a - b) * m.mesh3d[tri[0]] + a * m.mesh3d[tri[1]] + b * m.mesh3d[tri[2]];
    p += sigma * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    s.points.push_back(p);
    s.outlier.push_back(false);
  }
  const int outliers = int(outlier_fraction * count);
  for (int i = 0; i < outliers; ++i) {
    s.points.push_back(lo + (hi - lo).cwiseProduct(Eigen::Vector3d(uni(rng), uni(rng), uni(rng))));
    s.outlier.push_back(true);
  }
  return s;
}

}  // namespace docunfold::testing
