// The joint optimisation of the 3D page M and its flat twin M' (paper
// "Document image rectification using isometric mapping" and "Algorithm"),
// shared by init-mesh and optimize.
//
//   F = λ1 E_iso + λ2 E_dist + λ3 E_fair(M) + λ4 E_fair(M') + λ5 E_line + λ6 E_ray
//
// over the vertices V of M, V' of M' and the parameters of the feature lines.
// Usage (geometry-central style: a problem, options, a checkable result):
//
//   isometry::Problem problem;
//   problem.meshes = initial_pair;          // common/grid_mesh.h MeshPair
//   problem.points = sfm_points;            // world frame
//   isometry::SolveOptions options;         // paper defaults
//   isometry::Result result = isometry::Solve(problem, options);
//   result.meshes, result.point_inlier, result.report (one entry per outer
//   iteration: F, the six terms, inliers, markers, lines, wall time).
//
// Normalisation (why the paper's weights make sense here). Internally every
// length is divided by the bounding-box diagonal of the initial M (the
// "model size"; M and M' are shifted to their centroids and share the
// scale, so the isometry is unaffected). In that frame:
//  - E_dist = 1/H1 Σ_inliers β1|x − x^π|² + β2 <x − x^π, N>²  (a mean squared
//    distance in model-size units; noise of 0.2 % of the size gives ~4e-6);
//  - E_iso (IsoNormalization::kStrain, the default) = 1/Q Σ_quads Σ_i
//    (c_iso,i / ℓ²)², ℓ² the mean squared diagonal length of the quads of M'
//    at the start of the solve: the mean squared relative (strain) error of
//    the quads' diagonal lengths and angle, dimensionless and independent of
//    the grid resolution, so λ1 = 1 means the same on a 20x30 grid and after
//    three subdivisions. An edge-length error of 0.5 % costs ~1e-4:
//    isometry is much stiffer than the data term (paper does not stretch).
//    kRaw is the paper's literal sum of squared c_iso (4th order in lengths;
//    it weakens 4x per subdivision). With iso_edges > 0 each quad adds
//    |a|² - |a'|² of its four edges (same scale, times iso_edges / √2);
//  - E_fair = Σ |v_i − 2 v_j + v_k|² along every grid row and column (raw,
//    as in the paper; in model-size units, it weakens 4x per subdivision, as
//    the paper intends for the tiny λ3 that must not smooth creases away);
//  - E_line = 1/H2 Σ_markers on a line (n·p' − c)², E_ray = 1/H2 Σ_markers
//    w dist(p, ray)², w the marker's weight (1 but for optimize's hull
//    markers), H2 = the sum of the weights (in model-size units squared);
//  - the outlier distance φ is a fraction of the model size (0.06 as in the
//    paper "for a normalized model").
// Reported term values are in these units; meshes and lines are returned in
// the caller's units.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "common/grid_mesh.h"
#include "common/json_io.h"
#include "common/option_table_fwd.h"

namespace docunfold::isometry {

// λ1..λ6 of F. Defaults: the paper's values for the first round.
struct Weights {
  double iso = 1.0;      // λ1, E_iso
  double dist = 1.0;     // λ2, E_dist
  double fair3d = 1e-4;  // λ3, E_fair(M)
  double fair2d = 0.1;   // λ4, E_fair(M')
  double line = 1.0;     // λ5, E_line
  double ray = 1.0;      // λ6, E_ray
};

// A straight line in the plane of M': n·p' = offset with n = (cos θ, sin θ),
// in M' units. An unknown of F.
struct FeatureLine {
  double theta = 0;   // radians
  double offset = 0;  // M' units
  // θ is held at the nearest multiple of 90 degrees (only the offset is
  // fitted or varied): printed rows and rules run along the page's axes,
  // parallel or perpendicular to each other, which straightness alone does
  // not ask (the paper's E_line leaves M' free to shear).
  bool axis_aligned = false;
  Eigen::Vector2d Normal() const { return {std::cos(theta), std::sin(theta)}; }
  double SignedDistance(const Eigen::Vector2d& p) const { return Normal().dot(p) - offset; }
};

// A sample of a feature in the reference image: where its viewing ray meets
// M (triangle + barycentrics, the same on M'), the ray itself and the line it
// belongs to. p = Σ ω_i v_i on M, p' = Σ ω_i v'_i on M'.
struct Marker {
  SurfacePoint where;
  Eigen::Vector3d ray_origin = Eigen::Vector3d::Zero();      // world frame
  Eigen::Vector3d ray_direction = Eigen::Vector3d::UnitZ();  // unit, world frame
  int line = -1;  // index into Problem::lines; -1: only E_ray applies
  // Non-zero (unit, orthogonal to the ray): E_ray keeps only the component
  // of p - ray_origin along it, so the point is held to the plane through
  // the ray normal to `across` and may slide within it (an outline: the
  // plane through the camera centre and a tangent line of the silhouette).
  Eigen::Vector3d across = Eigen::Vector3d::Zero();
  double weight = 1;  // of its E_ray rows, and its share of H2 (> 0)
};

struct Problem {
  MeshPair meshes;                      // initial V (M) and V' (M')
  std::vector<Eigen::Vector3d> points;  // target points (SfM), world frame
  std::vector<Marker> markers;          // may be empty (then E_line = E_ray = 0)
  std::vector<FeatureLine> lines;       // initial line parameters
  // λ3's multiplier per fair triplet (NumFairTriplets of the grid, in
  // FairTriplet's order), or empty (1 everywhere): lets E_fair(M) spare
  // where the caller knows the page is creased.
  std::vector<double> fair3d_weights;
};

enum class IsoNormalization { kStrain, kRaw };
enum class Method { kGaussNewton, kLbfgs };
// How a Gauss-Newton step's normal equations are solved: sparse Cholesky
// (CHOLMOD supernodal, symbolic analysis reused), block-Jacobi conjugate
// gradients, or auto: CG everywhere, to the tighter coarse_cg_tolerance on
// grids of up to coarse_max_vertices.
enum class LinearSolver { kAuto, kDirect, kConjugateGradient };

// Called at the start of every outer iteration, after footpoints and
// outliers were updated and before the lines are fitted (refit_lines), the
// markers projected (project_markers) and the step taken: lets optimize
// recast markers and regroup them into lines. Meshes, markers and lines are
// in the caller's units.
struct OuterIterationContext {
  int iteration = 0;
  const MeshPair* meshes = nullptr;
  std::vector<Marker>* markers = nullptr;
  std::vector<FeatureLine>* lines = nullptr;
};

struct SolveOptions {
  Weights weights;
  double beta_point = 1.0;   // β1: point-to-point part of E_dist
  double beta_normal = 0.1;  // β2: point-to-tangent-plane part of E_dist
  // φ: a point is ignored while its distance to M exceeds this fraction of
  // the model size (bounding-box diagonal of M); re-decided every outer
  // iteration (progressive filtering). <= 0 keeps every point.
  double outlier_distance = 0.06;
  IsoNormalization iso_normalization = IsoNormalization::kStrain;
  // Weight of E_iso's edge-length rows against the paper's three diagonal
  // rows per quad (0 = the paper). The diagonals alone leave a quad of M free
  // to twist out of its plane, which lengthens its edges.
  double iso_edges = 0;

  Method method = Method::kGaussNewton;
  // Block-Jacobi CG: an inexact Gauss-Newton step (a few CG iterations to a
  // loose tolerance) is enough once the coarser rounds have settled the
  // smooth part, at a fraction of the cost of factorising the fine grids.
  // The coarse grids (the 21x31 first round) settle the blank paper and
  // need steps solved to 1e-3, which CG reaches in a fraction of CHOLMOD's
  // time there. See docs/decisions/optimize.md, "Conjugate gradients on the
  // fine grids" and "Conjugate gradients on the coarse grid, to 1e-3".
  LinearSolver linear_solver = LinearSolver::kAuto;
  int coarse_max_vertices = 1000;
  double coarse_cg_tolerance = 1e-3;  // relative residual, on coarse grids
  int coarse_cg_max_iterations = 3000;
  int cg_max_iterations = 40;     // per Gauss-Newton step
  double cg_tolerance = 3e-2;     // relative residual of the normal equations
  double initial_damping = 1e-4;  // Levenberg-Marquardt μ (× diag(JᵀJ))
  int lbfgs_iterations = 30;      // L-BFGS iterations per outer iteration
  int lbfgs_memory = 10;

  // Outer loop: footpoints/outliers/lines are recomputed, then one step; it
  // stops when |ΔF/F| < relative_tolerance between outer iterations (ε) or
  // after max_outer_iterations (Q).
  int max_outer_iterations = 100;
  double relative_tolerance = 0.01;
  // The solve stops at the outer iteration where |ΔF/F| < ε for the
  // converged_iterations-th time (1 = the paper: the first): one short step
  // (Levenberg-Marquardt raising its damping, markers re-decided) is a pause,
  // not convergence. Counted whether in a row or not, so that a solve whose
  // F keeps alternating between short and long steps still ends soon.
  int converged_iterations = 1;
  // Also stop once F has risen from one outer iteration to the next this
  // many times (it oscillates); 0 = never.
  int max_rises = 0;
  // Gauss-Newton: |ΔF/F| < ε does not count while the Levenberg-Marquardt
  // damping μ is above this (0 = always counts).
  double converged_max_damping = 0;

  // Lines are unknowns of F. They are solved for in closed form (total least
  // squares of their markers' p' = the exact minimiser of E_line for the
  // current M') at the start of every outer iteration and held during the
  // Gauss-Newton step (variable projection); L-BFGS treats them as ordinary
  // variables. false keeps them fixed at the given values under Gauss-Newton.
  bool refit_lines = true;
  // The paper's feature line projection: after the lines are fitted, move
  // every marker's p' onto its line and keep the face and barycentrics of
  // the moved point (found in M') as the marker's new surface point.
  bool project_markers = false;

  // OpenMP threads for footpoints, assembly and CG at most; each outer
  // iteration runs fewer while other processes keep cores busy (CpuShare).
  int num_threads = 2;
  std::function<void(const OuterIterationContext&)> on_outer_iteration;
};

// Values of the six terms (unweighted, in the normalised units above).
struct TermValues {
  double iso = 0, dist = 0, fair3d = 0, fair2d = 0, line = 0, ray = 0;
  double Weighted(const Weights& w) const {
    return w.iso * iso + w.dist * dist + w.fair3d * fair3d + w.fair2d * fair2d + w.line * line +
           w.ray * ray;
  }
};

struct IterationReport {
  int iteration = 0;
  double F = 0;  // Σ λ_k E_k after footpoints/outliers/lines were updated
  // F after this iteration's step with the same footpoints, outliers,
  // markers and lines (what the step minimises): never above F. The next
  // iteration's F differs from it by re-deciding those (NaN: no step taken).
  double F_after_step = std::numeric_limits<double>::quiet_NaN();
  TermValues terms;
  int inliers = 0;  // points within φ of M
  int outliers = 0;
  int markers = 0;
  int lines = 0;
  double seconds = 0;            // wall time since the solve started, at the end of this iteration
  double footpoint_seconds = 0;  // footpoints + outliers + lines
  double step_seconds = 0;       // assembly + linear solves (or L-BFGS batch)
  int linear_iterations = 0;     // factorisations, CG iterations or L-BFGS iterations
  double damping = 0;            // Levenberg-Marquardt μ after the step
  bool step_accepted = false;
  int threads = 1;  // OpenMP threads used (fewer than asked when other work is running)
};

struct SolveReport {
  std::vector<IterationReport> iterations;
  bool converged = false;
  std::string stop_reason;  // "converged", "max_iterations", "stalled"
  std::string method;       // "gauss-newton/cholmod", "gauss-newton/cg", "lbfgs"
  double model_size = 0;    // bounding-box diagonal of the initial M (caller's units)
  double seconds = 0;
  int num_vertices = 0;
  int num_points = 0;
};

struct Result {
  MeshPair meshes;
  std::vector<FeatureLine> lines;
  std::vector<Marker> markers;         // moved when project_markers is set
  std::vector<bool> point_inlier;      // final decision per Problem::points
  std::vector<double> point_distance;  // distance to the final M (caller's units; +inf when far)
  SolveReport report;
};

// Declares the solver's flags (weights, outliers, fairness, the method and
// its stopping rule) into `table`, bound to `options`' fields: the same flags
// in init-mesh and optimize, each with that stage's default.
void DeclareSolveOptions(OptionTable& table, SolveOptions* options);

// E_fair's triplets of vertices (three in a row along a grid row, then
// along a column), in the order of Problem::fair3d_weights.
std::vector<std::array<int, 3>> FairTriplets(const QuadGrid& grid);

// Minimises F from problem's initial values. Throws std::invalid_argument on
// an inconsistent problem (sizes, non-finite values, bad marker triangles).
Result Solve(const Problem& problem, const SolveOptions& options = {});

// F and its terms at the problem's values (footpoints, outliers computed as
// in the first outer iteration, lines as given).
struct Evaluation {
  double F = 0;
  TermValues terms;
  int inliers = 0;
  double model_size = 0;
};
Evaluation Evaluate(const Problem& problem, const SolveOptions& options = {});

// log.json material: the per-iteration report as JSON.
Json ToJson(const SolveReport& report);
Json ToJson(const TermValues& terms);

}  // namespace docunfold::isometry
