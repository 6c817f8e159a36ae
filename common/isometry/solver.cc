// Solve and Evaluate: the outer loop over footpoints, markers and lines, and
// one Gauss-Newton or L-BFGS step per outer iteration.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "common/cpu_share.h"
#include "common/isometry/gauss_newton.h"
#include "common/isometry/isometry.h"
#include "common/isometry/solver_internal.h"
#include "common/program.h"

namespace docunfold::isometry {

using internal::GaussNewton;
using internal::Work;

namespace {

// One for the process, so optimize's successive rounds go on measuring
// where the previous one stopped.
CpuShare& ProcessCpuShare() {
  static CpuShare share;
  return share;
}

// SolveOptions::on_outer_iteration with the meshes, markers and lines in
// the caller's units; takes back the markers and lines it leaves.
void CallOuterIteration(const SolveOptions& o, int it, Work& w) {
  using namespace internal;
  MeshPair meshes = Denormalise(w.state, w.frame);
  std::vector<Marker> markers;
  for (const Marker& m : w.data.markers) markers.push_back(DenormaliseMarker(m, w.frame));
  std::vector<FeatureLine> lines = DenormaliseLines(w.state, w.frame);
  o.on_outer_iteration({it, &meshes, &markers, &lines});
  w.data.markers.clear();
  w.data.marker_weights = 0;
  for (const Marker& m : markers) {
    w.data.markers.push_back(NormaliseMarker(m, w.frame));
    w.data.marker_weights += m.weight;
  }
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

// The lines' parameters for the current M' and, with project_markers, the
// markers moved onto them.
void UpdateLines(const SolveOptions& o, Work& w) {
  using namespace internal;
  if (w.data.markers.empty() || w.state.lines.empty()) return;
  for (FeatureLine& l : w.state.lines)  // the caller's may be slanted
    if (l.axis_aligned) l.theta = NearestAxisTheta(l.theta);
  if (o.refit_lines) FitLines(w.state, w.data);
  if (o.project_markers) ProjectMarkers(w.state, w.data);
}

SolveReport StartReport(const Problem& problem, const Work& w, const GaussNewton* gn) {
  SolveReport report;
  if (gn) {
    report.method = gn->direct() ? "gauss-newton/cholmod" : "gauss-newton/cg";
  } else {
    report.method = "lbfgs";
  }
  report.model_size = 1 / w.frame.scale;
  report.num_vertices = w.state.grid.NumVertices();
  report.num_points = int(problem.points.size());
  return report;
}

Result MakeResult(const Work& w) {
  using namespace internal;
  Result result;
  result.meshes = Denormalise(w.state, w.frame);
  result.lines = DenormaliseLines(w.state, w.frame);
  for (const Marker& m : w.data.markers) result.markers.push_back(DenormaliseMarker(m, w.frame));
  for (const Footpoint& f : w.data.footpoints) {
    result.point_inlier.push_back(f.inlier);
    result.point_distance.push_back(f.inlier ? f.distance / w.frame.scale
                                             : std::numeric_limits<double>::infinity());
  }
  return result;
}

}  // namespace

Evaluation Evaluate(const Problem& problem, const SolveOptions& options) {
  using namespace internal;
  Validate(problem);
  Work w = Normalise(problem, options);
  UpdateFootpoints(w.state, w.data, options.outlier_distance, std::max(1, options.num_threads));
  Evaluation e;
  e.terms = EvaluateTerms(w.state, w.data, std::max(1, options.num_threads));
  e.F = e.terms.Weighted(w.weights);
  e.inliers = w.data.num_inliers;
  e.model_size = 1 / w.frame.scale;
  return e;
}

Result Solve(const Problem& problem, const SolveOptions& o) {
  using namespace internal;
  const auto start = std::chrono::steady_clock::now();
#ifdef _OPENMP
  // The thread count is ours to choose (ProcessCpuShare), not libgomp's
  // from the 15-minute load average.
  omp_set_dynamic(0);
#endif
  Validate(problem);
  Work w = Normalise(problem, o);
  std::unique_ptr<GaussNewton> gn;
  if (o.method == Method::kGaussNewton) gn = std::make_unique<GaussNewton>(w.state.grid, o);
  SolveReport report = StartReport(problem, w, gn.get());

  double f_previous = 0;
  int rises = 0;
  int small_changes = 0;  // outer iterations so far with |ΔF/F| < ε
  for (int it = 0;; ++it) {
    IterationReport ir;
    ir.iteration = it;
    const auto t0 = std::chrono::steady_clock::now();
    // Re-decided every outer iteration: other work may start or end.
    const int threads = ProcessCpuShare().Threads(o.num_threads);
    if (gn) gn->set_threads(threads);
    ir.threads = threads;
    UpdateFootpoints(w.state, w.data, o.outlier_distance, threads);
    // The callback first: it may regroup markers into new lines, which are
    // then fitted and projected onto like any others.
    if (o.on_outer_iteration) CallOuterIteration(o, it, w);
    UpdateLines(o, w);
    ir.terms = EvaluateTerms(w.state, w.data, threads);
    ir.F = ir.terms.Weighted(w.weights);
    ir.inliers = w.data.num_inliers;
    ir.outliers = int(w.data.points.size()) - w.data.num_inliers;
    ir.markers = int(w.data.markers.size());
    ir.lines = int(w.state.lines.size());
    ir.footpoint_seconds = SecondsSince(t0);

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
      ir.seconds = SecondsSince(start);
      report.iterations.push_back(ir);
      break;
    }
    const auto t1 = std::chrono::steady_clock::now();
    if (gn) {
      ir.step_accepted = gn->Step(w.state, w.data, w.weights, &ir.linear_iterations);
      ir.damping = gn->damping();
    } else {
      ir.step_accepted = LbfgsStep(w.state, w.data, w.weights, o, &ir.linear_iterations);
    }
    ir.step_seconds = SecondsSince(t1);
    ir.F_after_step = SurrogateF(w.state, w.data, w.weights, threads);
    ir.seconds = SecondsSince(start);
    report.iterations.push_back(ir);
    f_previous = ir.F;
  }

  Result result = MakeResult(w);
  report.seconds = SecondsSince(start);
  result.report = std::move(report);
  return result;
}

}  // namespace docunfold::isometry
