#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <LBFGS.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Eigenvalues>
#include <Eigen/Sparse>

#include "common/cpu_share.h"
#include "common/isometry/block_matrix.h"
#include "common/isometry/isometry.h"
#include "common/isometry/mesh_index.h"
#include "common/isometry/residuals.h"

namespace docunfold::isometry {

using internal::GridBlockMatrix;
using internal::Row;
using internal::State;
using internal::StepData;
using internal::Vec5;

namespace {
// θ of an axis-aligned line: the nearest multiple of 90 degrees.
double NearestAxisTheta(double theta) {
  constexpr double kHalfPi = 1.57079632679489661923;
  return kHalfPi * std::round(theta / kHalfPi);
}
}  // namespace

namespace internal {
namespace {

// Adds the squares of the first `n` rows' values to `sum`, one by one.
void AddSquares(const Row* rows, int n, double* sum) {
  for (int i = 0; i < n; ++i) *sum += rows[i].value * rows[i].value;
}

// Items per chunk of OrderedSums. Chunks, not threads, fix the order in
// which floating-point sums are added, so F, and with it every step Levenberg-
// Marquardt accepts, is the same whatever number of threads runs (the solver
// re-decides that number every outer iteration from the machine's load).
constexpr int kSumChunk = 1024;

// Per chunk of [0, n): add(i, acc) for its items in order, into acc[0..K).
// Returns the chunks' sums added in chunk order.
template <int K, class Add>
std::array<double, K> OrderedSums(int n, int threads, Add&& add) {
  const int chunks = (n + kSumChunk - 1) / kSumChunk;
  std::vector<std::array<double, K>> part(static_cast<size_t>(chunks));
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && chunks > 1)
  for (int c = 0; c < chunks; ++c) {
    std::array<double, K> acc{};
    Row rows[kMaxRowsPerItem];
    for (int i = c * kSumChunk; i < std::min(n, (c + 1) * kSumChunk); ++i) add(i, rows, acc);
    part[size_t(c)] = acc;
  }
  std::array<double, K> total{};
  for (const auto& acc : part)
    for (int k = 0; k < K; ++k) total[size_t(k)] += acc[size_t(k)];
  return total;
}

}  // namespace

TermValues EvaluateTerms(const State& s, const StepData& data, int threads) {
  const int quads = s.grid.NumQuads(), points = int(data.points.size());
  const int triplets = NumFairTriplets(s.grid), markers = int(data.markers.size());
  threads = quads > 2000 ? threads : 1;
  const double iso = OrderedSums<1>(quads, threads, [&](int q, Row* rows, auto& acc) {
    AddSquares(rows, IsoRows(s, data, q, rows), &acc[0]);
  })[0];
  const double dist = OrderedSums<1>(points, threads, [&](int p, Row* rows, auto& acc) {
    AddSquares(rows, DistRows(s, data, p, rows), &acc[0]);
  })[0];
  const auto fair = OrderedSums<2>(triplets, threads, [&](int t, Row* rows, auto& acc) {
    AddSquares(rows, FairRows(s, t, false, rows), &acc[0]);
    AddSquares(rows, FairRows(s, t, true, rows), &acc[1]);
  });
  const auto feature = OrderedSums<2>(markers, threads, [&](int m, Row* rows, auto& acc) {
    AddSquares(rows, LineRows(s, data, m, rows), &acc[0]);
    AddSquares(rows, RayRows(s, data, m, rows), &acc[1]);
  });
  const double fair3d = fair[0], fair2d = fair[1], line = feature[0], ray = feature[1];
  TermValues t;
  t.iso = iso;
  t.dist = dist;
  t.fair3d = fair3d;
  t.fair2d = fair2d;
  t.line = line;
  t.ray = ray;
  return t;
}

}  // namespace internal

namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// The normalised frame: lengths divided by the bounding-box diagonal of M,
// M and M' centred on their vertex centroids.
struct Frame {
  double scale = 1;  // normalised = (x - center) * scale
  Eigen::Vector3d center3 = Eigen::Vector3d::Zero();
  Eigen::Vector2d center2 = Eigen::Vector2d::Zero();
};

Frame FrameOf(const MeshPair& m) {
  Frame f;
  Eigen::Vector3d lo = m.mesh3d[0], hi = lo, sum3 = Eigen::Vector3d::Zero();
  Eigen::Vector2d sum2 = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < m.mesh3d.size(); ++i) {
    lo = lo.cwiseMin(m.mesh3d[i]);
    hi = hi.cwiseMax(m.mesh3d[i]);
    sum3 += m.mesh3d[i];
    sum2 += m.mesh2d[i];
  }
  const double diagonal = (hi - lo).norm();
  if (!(diagonal > 0) || !std::isfinite(diagonal))
    throw std::invalid_argument("isometry: M is degenerate (zero or infinite size)");
  f.scale = 1 / diagonal;
  f.center3 = sum3 / double(m.mesh3d.size());
  f.center2 = sum2 / double(m.mesh2d.size());
  return f;
}

void Validate(const Problem& p) {
  const QuadGrid& g = p.meshes.grid;
  if (g.nx < 2 || g.ny < 2) throw std::invalid_argument("isometry: grid smaller than 2x2");
  if (int(p.meshes.mesh3d.size()) != g.NumVertices() ||
      int(p.meshes.mesh2d.size()) != g.NumVertices())
    throw std::invalid_argument("isometry: mesh sizes do not match the grid");
  for (const auto& v : p.meshes.mesh3d)
    if (!v.allFinite()) throw std::invalid_argument("isometry: non-finite vertex in M");
  for (const auto& v : p.meshes.mesh2d)
    if (!v.allFinite()) throw std::invalid_argument("isometry: non-finite vertex in M'");
  for (const auto& x : p.points)
    if (!x.allFinite()) throw std::invalid_argument("isometry: non-finite target point");
  const int triangles = 2 * g.NumQuads();
  for (const Marker& m : p.markers) {
    if (m.where.triangle < 0 || m.where.triangle >= triangles)
      throw std::invalid_argument("isometry: marker on triangle " +
                                  std::to_string(m.where.triangle) + " outside the grid");
    if (m.line >= int(p.lines.size()))
      throw std::invalid_argument("isometry: marker on line " + std::to_string(m.line) + " of " +
                                  std::to_string(p.lines.size()));
    if (!m.ray_origin.allFinite() || !(m.ray_direction.norm() > 0) || !m.where.bary.allFinite() ||
        !m.across.allFinite())
      throw std::invalid_argument("isometry: marker with a bad ray or barycentrics");
  }
}

// Everything the outer loop works on, in the normalised frame.
struct Work {
  Frame frame;
  State state;
  StepData data;
  Weights weights;
};

Work Normalise(const Problem& p, const SolveOptions& o) {
  Work w;
  w.frame = FrameOf(p.meshes);
  const Frame& f = w.frame;
  w.state.grid = p.meshes.grid;
  for (const auto& v : p.meshes.mesh3d) w.state.v3.push_back((v - f.center3) * f.scale);
  for (const auto& v : p.meshes.mesh2d) w.state.v2.push_back((v - f.center2) * f.scale);
  for (FeatureLine l : p.lines) {
    l.offset = (l.offset - l.Normal().dot(f.center2)) * f.scale;
    w.state.lines.push_back(l);
  }
  for (const auto& x : p.points) w.data.points.push_back((x - f.center3) * f.scale);
  w.data.footpoints.resize(p.points.size());
  for (Marker m : p.markers) {
    m.ray_origin = (m.ray_origin - f.center3) * f.scale;
    m.ray_direction.normalize();
    w.data.markers.push_back(m);
  }
  w.data.beta_point = o.beta_point;
  w.data.beta_normal = o.beta_normal;
  if (o.iso_normalization == IsoNormalization::kStrain) {
    // c_iso divided by ℓ², the mean squared diagonal length of the quads of
    // M' at the start (of M when M' is degenerate): rows are strains of an
    // average quad. (Dividing each quad by its own ℓ_q² was tried: it lets
    // the small quads of perspective-compressed grid corners dominate and
    // measured worse, 2.0 % vs 0.9 % edge error on set08 and 0.44 % vs
    // 0.35 % on r01.)
    const int quads = w.state.grid.NumQuads();
    auto mean_diag2 = [&](const auto& v) {
      double sum = 0;
      for (int q = 0; q < quads; ++q) {
        const auto c = w.state.grid.Quad(q);
        sum += 0.5 * ((v[c[0]] - v[c[2]]).squaredNorm() + (v[c[1]] - v[c[3]]).squaredNorm());
      }
      return sum / quads;
    };
    double mean = mean_diag2(w.state.v2);
    if (!(mean > 0)) mean = mean_diag2(w.state.v3);
    if (!(mean > 0)) throw std::invalid_argument("isometry: every quad is degenerate");
    w.data.iso_scale = 1 / (mean * std::sqrt(double(quads)));
  } else {
    w.data.iso_scale = 1;
  }
  w.data.iso_edge_weight = o.iso_edges;
  w.weights = o.weights;
  return w;
}

MeshPair Denormalise(const State& s, const Frame& f) {
  MeshPair m;
  m.grid = s.grid;
  for (const auto& v : s.v3) m.mesh3d.push_back(v / f.scale + f.center3);
  for (const auto& v : s.v2) m.mesh2d.push_back(v / f.scale + f.center2);
  return m;
}

std::vector<FeatureLine> DenormaliseLines(const State& s, const Frame& f) {
  std::vector<FeatureLine> out;
  for (FeatureLine l : s.lines) {
    l.offset = l.offset / f.scale + l.Normal().dot(f.center2);
    out.push_back(l);
  }
  return out;
}

Marker DenormaliseMarker(Marker m, const Frame& f) {
  m.ray_origin = m.ray_origin / f.scale + f.center3;
  return m;
}

Marker NormaliseMarker(Marker m, const Frame& f) {
  m.ray_origin = (m.ray_origin - f.center3) * f.scale;
  m.ray_direction.normalize();
  return m;
}

// Footpoints of every target point on M, and the outlier decision.
void UpdateFootpoints(const State& s, StepData& data, double phi, int threads) {
  if (data.points.empty()) {
    data.num_inliers = 0;
    return;
  }
  const std::vector<Triangle> triangles = s.grid.Triangles();
  TriangleMeshIndex index(s.v3, triangles);
  const double max_distance = phi > 0 ? phi : std::numeric_limits<double>::infinity();
  const int n = int(data.points.size());
  int inliers = 0;
#pragma omp parallel for num_threads(threads) reduction(+ : inliers) schedule(dynamic, 256) if (threads > 1 && n > 2000)
  for (int i = 0; i < n; ++i) {
    internal::Footpoint& f = data.footpoints[i];
    const auto c = index.Closest(data.points[i], max_distance);
    if (!c) {
      f.inlier = false;
      f.distance = std::numeric_limits<double>::infinity();
      continue;
    }
    f.triangle = c->triangle;
    f.bary = c->bary;
    f.distance = c->distance;
    const Triangle& t = triangles[c->triangle];
    const Eigen::Vector3d normal = (s.v3[t[1]] - s.v3[t[0]]).cross(s.v3[t[2]] - s.v3[t[0]]);
    if (normal.norm() > 0) f.normal = normal.normalized();
    f.inlier = true;
    ++inliers;
  }
  data.num_inliers = inliers;
}

Eigen::Vector2d FlatPoint(const State& s, const SurfacePoint& w) {
  const Triangle t = internal::TriangleOf(s.grid, w.triangle);
  return w.bary[0] * s.v2[t[0]] + w.bary[1] * s.v2[t[1]] + w.bary[2] * s.v2[t[2]];
}

// Total least squares line through each line's markers: the exact minimiser
// of E_line over (θ, offset) for the current M'.
void FitLines(State& s, const StepData& data) {
  const int n = int(s.lines.size());
  std::vector<Eigen::Vector2d> sum(n, Eigen::Vector2d::Zero());
  std::vector<Eigen::Matrix2d> outer(n, Eigen::Matrix2d::Zero());
  std::vector<int> count(n, 0);
  for (const Marker& m : data.markers) {
    if (m.line < 0) continue;
    const Eigen::Vector2d p = FlatPoint(s, m.where);
    sum[m.line] += p;
    outer[m.line] += p * p.transpose();
    ++count[m.line];
  }
  for (int l = 0; l < n; ++l) {
    if (count[l] < 2) continue;
    const Eigen::Vector2d mean = sum[l] / count[l];
    const Eigen::Matrix2d scatter = outer[l] - count[l] * mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
    Eigen::Vector2d normal = eig.eigenvectors().col(0);
    if (normal.dot(s.lines[l].Normal()) < 0) normal = -normal;
    double theta = std::atan2(normal.y(), normal.x());
    if (s.lines[l].axis_aligned) {
      theta = NearestAxisTheta(theta);
      normal = Eigen::Vector2d(std::cos(theta), std::sin(theta));
    }
    s.lines[l].theta = theta;
    s.lines[l].offset = normal.dot(mean);
  }
}

// Feature line projection: p' onto its line, then the new face and
// barycentrics of the moved point in M'.
void ProjectMarkers(const State& s, StepData& data) {
  MeshPair flat;
  flat.grid = s.grid;
  flat.mesh2d = s.v2;
  FlatMeshLocator locator(flat);
  for (Marker& m : data.markers) {
    if (m.line < 0) continue;
    const FeatureLine& l = s.lines[m.line];
    const Eigen::Vector2d p = FlatPoint(s, m.where);
    const Eigen::Vector2d moved = p - l.SignedDistance(p) * l.Normal();
    if (auto w = locator.Locate(moved)) m.where = *w;
  }
}

double WeightedF(const TermValues& t, const Weights& w) { return t.Weighted(w); }

// Surrogate F (footpoints, normals and — under Gauss-Newton — lines fixed)
// at a state.
double SurrogateF(const State& s, const StepData& data, const Weights& w, int threads) {
  return WeightedF(internal::EvaluateTerms(s, data, threads), w);
}

// Applies a step δ (5 unknowns per vertex).
State Moved(const State& s, const Eigen::VectorXd& delta) {
  State t = s;
  for (size_t i = 0; i < t.v3.size(); ++i) {
    t.v3[i] += delta.segment<3>(5 * i);
    t.v2[i] += delta.segment<2>(5 * i + 3);
  }
  return t;
}

// ---------------------------------------------------------------------------
// Gauss-Newton / Levenberg-Marquardt.

class GaussNewton {
 public:
  GaussNewton(const QuadGrid& grid, const SolveOptions& o)
      : o_(o), H_(grid), threads_(std::max(1, o.num_threads)) {
    const bool direct =
        o.linear_solver == LinearSolver::kDirect ||
        (o.linear_solver == LinearSolver::kAuto && grid.NumVertices() <= o.direct_max_vertices);
    direct_ = direct;
    mu_ = o.initial_damping;
  }
  bool direct() const { return direct_; }
  void set_threads(int threads) { threads_ = std::max(1, threads); }
  double damping() const { return mu_; }

  // One damped Gauss-Newton step with the data held fixed; returns whether
  // F decreased. `linear_iterations` counts CG iterations or factorisations.
  bool Step(State& s, const StepData& data, const Weights& w, int* linear_iterations) {
    const int n = s.grid.NumVertices();
    Eigen::VectorXd g = Eigen::VectorXd::Zero(5 * n);
    const double f0 = Assemble(s, data, w, g);
    Eigen::VectorXd scale = H_.Diagonal();
    const double floor = 1e-12 * std::max(1e-300, scale.maxCoeff());
    for (int i = 0; i < scale.size(); ++i) scale[i] = std::max(scale[i], floor);
    *linear_iterations = 0;
    for (int attempt = 0; attempt < 12; ++attempt) {
      Eigen::VectorXd delta;
      const Eigen::VectorXd shift = mu_ * scale;
      const bool solved = direct_ ? SolveDirect(shift, g, delta, linear_iterations)
                                  : SolveCg(shift, g, delta, linear_iterations);
      if (!solved) {
        mu_ = std::max(mu_ * 10, 1e-8);
        continue;
      }
      Eigen::VectorXd Hd;
      H_.Multiply(delta, Hd, threads_);
      const double predicted = -(2 * delta.dot(g) + delta.dot(Hd));
      State trial = Moved(s, delta);
      const double f1 = SurrogateF(trial, data, w, threads_);
      if (f1 < f0 && predicted > 0) {
        const double rho = (f0 - f1) / predicted;
        s = std::move(trial);
        mu_ *= std::max(1.0 / 3, 1 - std::pow(2 * rho - 1, 3));
        mu_ = std::max(mu_, 1e-12);
        nu_ = 2;
        return true;
      }
      mu_ *= nu_;
      nu_ *= 2;
    }
    return false;
  }

 private:
  // JᵀJ into H_, Jᵀr into g; returns F. Rows of quads (and fairness
  // triplets) of one colour share no vertex, so they are added in parallel.
  double Assemble(const State& s, const StepData& data, const Weights& w, Eigen::VectorXd& g) {
    H_.SetZero();
    const QuadGrid& grid = s.grid;
    const bool parallel = threads_ > 1 && grid.NumVertices() > 2000;
    auto add = [&](double weight, const Row& r) {
      const double k = std::sqrt(weight);
      const double value = k * r.value;
      Vec5 da[4];
      for (int a = 0; a < r.count; ++a) da[a] = k * r.d[a];
      for (int a = 0; a < r.count; ++a) {
        g.segment<5>(5 * r.vertex[a]) += da[a] * value;
        for (int b = a; b < r.count; ++b) H_.AddOuter(r.vertex[a], da[a], r.vertex[b], da[b]);
      }
      return value * value;
    };
    double f = 0;
    // Per grid row or line, then added in order: F does not depend on the
    // number of threads (see kSumChunk).
    std::vector<double> part(size_t(std::max(grid.nx, grid.ny)), 0.0);
    if (w.iso > 0)
      for (int colour = 0; colour < 4; ++colour) {
        const int r0 = colour / 2, c0 = colour % 2;
#pragma omp parallel for num_threads(threads_) schedule(static) if (parallel)
        for (int r = r0; r < grid.ny - 1; r += 2) {
          Row rows[internal::kMaxRowsPerItem];
          double sum = 0;
          for (int c = c0; c < grid.nx - 1; c += 2) {
            const int q = r * (grid.nx - 1) + c;
            const int m = internal::IsoRows(s, data, q, rows);
            for (int i = 0; i < m; ++i) sum += add(w.iso, rows[i]);
          }
          part[size_t(r)] = sum;
        }
        for (int r = r0; r < grid.ny - 1; r += 2) f += part[size_t(r)];
      }
    // Fairness: triplets along rows come first, then along columns (see
    // FairTriplet); centres three apart along the line share no vertex.
    const int along_rows = std::max(0, grid.ny * (grid.nx - 2));
    const int along_cols = std::max(0, grid.nx * (grid.ny - 2));
    for (int phase = 0; phase < 2; ++phase) {
      const int lines = phase == 0 ? grid.ny : grid.nx;
      const int per_line = phase == 0 ? grid.nx - 2 : grid.ny - 2;
      if (per_line <= 0 || (w.fair3d <= 0 && w.fair2d <= 0)) continue;
      for (int colour = 0; colour < 3; ++colour) {
#pragma omp parallel for num_threads(threads_) schedule(static) if (parallel)
        for (int l = 0; l < lines; ++l) {
          Row rows[3];
          double sum = 0;
          for (int k = colour; k < per_line; k += 3) {
            const int t = (phase == 0 ? 0 : along_rows) + l * per_line + k;
            if (w.fair3d > 0) {
              const int m = internal::FairRows(s, t, false, rows);
              for (int i = 0; i < m; ++i) sum += add(w.fair3d, rows[i]);
            }
            if (w.fair2d > 0) {
              const int m = internal::FairRows(s, t, true, rows);
              for (int i = 0; i < m; ++i) sum += add(w.fair2d, rows[i]);
            }
          }
          part[size_t(l)] = sum;
        }
        for (int l = 0; l < lines; ++l) f += part[size_t(l)];
      }
    }
    (void)along_cols;
    Row rows[4];
    if (w.dist > 0)
      for (int p = 0; p < int(data.points.size()); ++p) {
        const int m = internal::DistRows(s, data, p, rows);
        for (int i = 0; i < m; ++i) f += add(w.dist, rows[i]);
      }
    for (int mk = 0; mk < int(data.markers.size()); ++mk) {
      if (w.line > 0) {
        const int m = internal::LineRows(s, data, mk, rows);
        for (int i = 0; i < m; ++i) f += add(w.line, rows[i]);
      }
      if (w.ray > 0) {
        const int m = internal::RayRows(s, data, mk, rows);
        for (int i = 0; i < m; ++i) f += add(w.ray, rows[i]);
      }
    }
    return f;
  }

  bool SolveDirect(const Eigen::VectorXd& shift, const Eigen::VectorXd& g, Eigen::VectorXd& delta,
                   int* iterations) {
    H_.ToSparseUpper(sparse_, shift);
    if (!cholmod_) {
      cholmod_ = std::make_unique<
          Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Upper>>();
      cholmod_->analyzePattern(sparse_);
    }
    cholmod_->factorize(sparse_);
    ++*iterations;
    if (cholmod_->info() != Eigen::Success) return false;
    delta = cholmod_->solve(-g);
    return cholmod_->info() == Eigen::Success && delta.allFinite();
  }

  // Block-Jacobi preconditioned conjugate gradients on (H + shift) δ = -g.
  bool SolveCg(const Eigen::VectorXd& shift, const Eigen::VectorXd& g, Eigen::VectorXd& delta,
               int* iterations) {
    const int n = H_.NumVertices();
    const bool parallel = threads_ > 1 && n > 2000;
    precond_.resize(n);
    bool ok = true;
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(&& : ok) if (parallel)
    for (int i = 0; i < n; ++i) {
      internal::Mat5 d = H_.Block(i, 0);
      d.diagonal() += shift.segment<5>(5 * i);
      Eigen::LLT<internal::Mat5> llt(d);
      if (llt.info() != Eigen::Success) {
        ok = false;
        continue;
      }
      precond_[i] = llt.solve(internal::Mat5::Identity());
    }
    if (!ok) return false;
    auto apply_precond = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
      z.resize(r.size());
#pragma omp parallel for num_threads(threads_) schedule(static) if (parallel)
      for (int i = 0; i < n; ++i) z.segment<5>(5 * i).noalias() = precond_[i] * r.segment<5>(5 * i);
    };
    auto apply_a = [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
      H_.Multiply(x, y, threads_);
      y += shift.cwiseProduct(x);
    };
    delta = Eigen::VectorXd::Zero(g.size());
    Eigen::VectorXd r = -g, z, p, ap;
    const double b_norm = r.norm();
    if (!(b_norm > 0)) return true;
    apply_precond(r, z);
    p = z;
    double rz = r.dot(z);
    for (int it = 0; it < o_.cg_max_iterations; ++it) {
      apply_a(p, ap);
      const double pap = p.dot(ap);
      if (!(pap > 0)) break;
      const double alpha = rz / pap;
      delta += alpha * p;
      r -= alpha * ap;
      ++*iterations;
      if (r.norm() <= o_.cg_tolerance * b_norm) break;
      apply_precond(r, z);
      const double rz_new = r.dot(z);
      p = z + (rz_new / rz) * p;
      rz = rz_new;
    }
    return delta.allFinite();
  }

  const SolveOptions& o_;
  GridBlockMatrix H_;
  int threads_ = 1;
  bool direct_ = true;
  double mu_ = 1e-4;
  double nu_ = 2;
  Eigen::SparseMatrix<double> sparse_;
  std::vector<internal::Mat5, Eigen::aligned_allocator<internal::Mat5>> precond_;
  std::unique_ptr<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Upper>> cholmod_;
};

// ---------------------------------------------------------------------------
// L-BFGS on V, V' and the line parameters (footpoints held fixed).

class LbfgsObjective {
 public:
  LbfgsObjective(const State& s, const StepData& data, const Weights& w)
      : base_(s), data_(data), w_(w) {}

  static Eigen::VectorXd Pack(const State& s) {
    const int n = int(s.v3.size());
    Eigen::VectorXd x(5 * n + 2 * s.lines.size());
    for (int i = 0; i < n; ++i) {
      x.segment<3>(5 * i) = s.v3[i];
      x.segment<2>(5 * i + 3) = s.v2[i];
    }
    for (size_t l = 0; l < s.lines.size(); ++l) {
      x[5 * n + 2 * l] = s.lines[l].theta;
      x[5 * n + 2 * l + 1] = s.lines[l].offset;
    }
    return x;
  }
  void Unpack(const Eigen::VectorXd& x, State& s) const {
    const int n = int(s.v3.size());
    for (int i = 0; i < n; ++i) {
      s.v3[i] = x.segment<3>(5 * i);
      s.v2[i] = x.segment<2>(5 * i + 3);
    }
    for (size_t l = 0; l < s.lines.size(); ++l) {
      s.lines[l].theta = x[5 * n + 2 * l];
      s.lines[l].offset = x[5 * n + 2 * l + 1];
    }
  }

  double operator()(const Eigen::VectorXd& x, Eigen::VectorXd& grad) {
    State& s = scratch_;
    if (s.v3.empty()) s = base_;
    Unpack(x, s);
    grad.setZero(x.size());
    const int n = int(s.v3.size());
    double f = 0;
    internal::ForEachRow(s, data_, [&](int term, const Row& r) {
      const double weight = internal::WeightOf(w_, term);
      if (weight <= 0) return;
      f += weight * r.value * r.value;
      const double k = 2 * weight * r.value;
      for (int a = 0; a < r.count; ++a) grad.segment<5>(5 * r.vertex[a]) += k * r.d[a];
      if (r.line >= 0) {
        if (!s.lines[r.line].axis_aligned) grad[5 * n + 2 * r.line] += k * r.d_theta;
        grad[5 * n + 2 * r.line + 1] += k * r.d_offset;
      }
    });
    ++evaluations_;
    return f;
  }
  int evaluations() const { return evaluations_; }

 private:
  const State& base_;
  const StepData& data_;
  const Weights& w_;
  State scratch_;
  int evaluations_ = 0;
};

bool LbfgsStep(State& s, const StepData& data, const Weights& w, const SolveOptions& o,
               int* iterations) {
  LBFGSpp::LBFGSParam<double> param;
  param.m = o.lbfgs_memory;
  param.max_iterations = o.lbfgs_iterations;
  param.epsilon = 1e-14;
  param.epsilon_rel = 0;
  param.max_linesearch = 40;
  param.linesearch = LBFGSpp::LBFGS_LINESEARCH_BACKTRACKING_STRONG_WOLFE;
  LBFGSpp::LBFGSSolver<double, LBFGSpp::LineSearchNocedalWright> solver(param);
  LbfgsObjective objective(s, data, w);
  Eigen::VectorXd x = LbfgsObjective::Pack(s), best = x;
  Eigen::VectorXd grad;
  const double f0 = objective(x, grad);
  double fx = f0;
  try {
    *iterations = solver.minimize(objective, x, fx);
    best = x;
  } catch (const std::exception& e) {
    if (std::getenv("DOCUNFOLD_DEBUG_LBFGS")) fprintf(stderr, "lbfgs: %s\n", e.what());
    // Line search failures near the optimum: keep the best point seen, if any.
    Eigen::VectorXd g2;
    fx = x.allFinite() ? objective(x, g2) : f0;
    if (fx < f0) best = x;
    *iterations = o.lbfgs_iterations;
  }
  if (!(fx < f0)) return false;
  objective.Unpack(best, s);
  return true;
}

// One for the process, so optimize's successive rounds go on measuring
// where the previous one stopped.
CpuShare& ProcessCpuShare() {
  static CpuShare share;
  return share;
}

Json IterationJson(const IterationReport& it) {
  Json j;
  j["iteration"] = it.iteration;
  j["F"] = it.F;
  j["terms"] = ToJson(it.terms);
  j["inliers"] = it.inliers;
  j["outliers"] = it.outliers;
  j["markers"] = it.markers;
  j["lines"] = it.lines;
  j["seconds"] = it.seconds;
  j["footpoint_seconds"] = it.footpoint_seconds;
  j["step_seconds"] = it.step_seconds;
  j["linear_iterations"] = it.linear_iterations;
  j["damping"] = it.damping;
  j["step_accepted"] = it.step_accepted;
  j["threads"] = it.threads;
  if (std::isfinite(it.F_after_step)) j["F_after_step"] = it.F_after_step;
  return j;
}

}  // namespace

Json ToJson(const TermValues& t) {
  return Json{{"iso", t.iso},       {"dist", t.dist}, {"fair3d", t.fair3d},
              {"fair2d", t.fair2d}, {"line", t.line}, {"ray", t.ray}};
}

Json ToJson(const SolveReport& r) {
  Json j;
  j["method"] = r.method;
  j["converged"] = r.converged;
  j["stop_reason"] = r.stop_reason;
  j["model_size"] = r.model_size;
  j["seconds"] = r.seconds;
  j["vertices"] = r.num_vertices;
  j["points"] = r.num_points;
  j["iterations"] = Json::array();
  for (const IterationReport& it : r.iterations) j["iterations"].push_back(IterationJson(it));
  return j;
}

Evaluation Evaluate(const Problem& problem, const SolveOptions& options) {
  Validate(problem);
  Work w = Normalise(problem, options);
  UpdateFootpoints(w.state, w.data, options.outlier_distance, std::max(1, options.num_threads));
  Evaluation e;
  e.terms = internal::EvaluateTerms(w.state, w.data, std::max(1, options.num_threads));
  e.F = e.terms.Weighted(w.weights);
  e.inliers = w.data.num_inliers;
  e.model_size = 1 / w.frame.scale;
  return e;
}

Result Solve(const Problem& problem, const SolveOptions& o) {
  const auto start = Clock::now();
#ifdef _OPENMP
  // The thread count is ours to choose (ProcessCpuShare), not libgomp's
  // from the 15-minute load average.
  omp_set_dynamic(0);
#endif
  Validate(problem);
  Work w = Normalise(problem, o);
  std::unique_ptr<GaussNewton> gn;
  SolveReport report;
  if (o.method == Method::kGaussNewton) {
    gn = std::make_unique<GaussNewton>(w.state.grid, o);
    report.method = gn->direct() ? "gauss-newton/cholmod" : "gauss-newton/cg";
  } else {
    report.method = "lbfgs";
  }
  report.model_size = 1 / w.frame.scale;
  report.num_vertices = w.state.grid.NumVertices();
  report.num_points = int(problem.points.size());

  double f_previous = 0;
  int rises = 0;
  int small_changes = 0;  // outer iterations so far with |ΔF/F| < ε
  for (int it = 0;; ++it) {
    IterationReport ir;
    ir.iteration = it;
    auto t0 = Clock::now();
    // Re-decided every outer iteration: other work may start or end.
    const int threads = ProcessCpuShare().Threads(o.num_threads);
    if (gn) gn->set_threads(threads);
    ir.threads = threads;
    UpdateFootpoints(w.state, w.data, o.outlier_distance, threads);
    // The callback first: it may regroup markers into new lines, which are
    // then fitted and projected onto like any others.
    if (o.on_outer_iteration) {
      MeshPair meshes = Denormalise(w.state, w.frame);
      std::vector<Marker> markers;
      for (const Marker& m : w.data.markers) markers.push_back(DenormaliseMarker(m, w.frame));
      std::vector<FeatureLine> lines = DenormaliseLines(w.state, w.frame);
      o.on_outer_iteration({it, &meshes, &markers, &lines});
      w.data.markers.clear();
      for (const Marker& m : markers) w.data.markers.push_back(NormaliseMarker(m, w.frame));
      w.state.lines.clear();
      for (FeatureLine l : lines) {
        l.offset = (l.offset - l.Normal().dot(w.frame.center2)) * w.frame.scale;
        w.state.lines.push_back(l);
      }
      Problem check;  // the callback may have broken the markers
      check.meshes = meshes;
      check.markers = markers;
      check.lines = lines;
      Validate(check);
    }
    if (!w.data.markers.empty() && !w.state.lines.empty()) {
      for (FeatureLine& l : w.state.lines)  // the caller's may be slanted
        if (l.axis_aligned) l.theta = NearestAxisTheta(l.theta);
      if (o.refit_lines) FitLines(w.state, w.data);
      if (o.project_markers) ProjectMarkers(w.state, w.data);
    }
    ir.terms = internal::EvaluateTerms(w.state, w.data, threads);
    ir.F = ir.terms.Weighted(w.weights);
    ir.inliers = w.data.num_inliers;
    ir.outliers = int(w.data.points.size()) - w.data.num_inliers;
    ir.markers = int(w.data.markers.size());
    ir.lines = int(w.state.lines.size());
    ir.footpoint_seconds = Since(t0);

    // A step Levenberg-Marquardt damped hard lowers F little without F being
    // near a minimum: that is no convergence (optionally).
    const bool damped =
        gn && o.converged_max_damping > 0 && gn->damping() > o.converged_max_damping;
    const bool small_change =
        it > 0 && !damped &&
        std::abs(ir.F - f_previous) <= o.relative_tolerance * std::abs(f_previous);
    small_changes += small_change;
    const bool converged = small_change && small_changes >= std::max(1, o.converged_iterations);
    // F measured after re-deciding footpoints and markers can oscillate
    // without settling; then |ΔF/F| falls below ε only by chance.
    if (it > 0 && ir.F > f_previous) ++rises;
    const bool oscillating = o.max_rises > 0 && rises >= o.max_rises;
    if (converged || oscillating || it >= o.max_outer_iterations) {
      report.converged = converged || oscillating;
      report.stop_reason = converged ? "converged" : oscillating ? "oscillating" : "max_iterations";
      ir.seconds = Since(start);
      report.iterations.push_back(ir);
      break;
    }
    auto t1 = Clock::now();
    if (gn) {
      ir.step_accepted = gn->Step(w.state, w.data, w.weights, &ir.linear_iterations);
      ir.damping = gn->damping();
    } else {
      ir.step_accepted = LbfgsStep(w.state, w.data, w.weights, o, &ir.linear_iterations);
    }
    ir.step_seconds = Since(t1);
    ir.F_after_step = SurrogateF(w.state, w.data, w.weights, threads);
    ir.seconds = Since(start);
    report.iterations.push_back(ir);
    f_previous = ir.F;
  }

  Result result;
  result.meshes = Denormalise(w.state, w.frame);
  result.lines = DenormaliseLines(w.state, w.frame);
  for (const Marker& m : w.data.markers) result.markers.push_back(DenormaliseMarker(m, w.frame));
  for (const internal::Footpoint& f : w.data.footpoints) {
    result.point_inlier.push_back(f.inlier);
    result.point_distance.push_back(f.inlier ? f.distance / w.frame.scale
                                             : std::numeric_limits<double>::infinity());
  }
  report.seconds = Since(start);
  result.report = std::move(report);
  return result;
}

}  // namespace docunfold::isometry
