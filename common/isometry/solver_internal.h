// Internal to docunfold_isometry: the parts of Solve, one job per file —
// the normalised frame (normalise.cc), what each outer iteration
// re-decides (outer_steps.cc), F at a state (terms.cc), the L-BFGS step
// (lbfgs.cc); the Gauss-Newton step has its own header (gauss_newton.h).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "common/grid_mesh.h"
#include "common/isometry/isometry.h"
#include "common/isometry/residuals.h"

namespace docunfold::isometry::internal {

// --- normalise.cc

// The normalised frame: lengths divided by the bounding-box diagonal of M,
// M and M' centred on their vertex centroids.
struct Frame {
  double scale = 1;  // normalised = (x - center) * scale
  Eigen::Vector3d center3 = Eigen::Vector3d::Zero();
  Eigen::Vector2d center2 = Eigen::Vector2d::Zero();
};

Frame FrameOf(const MeshPair& m);

// Throws std::invalid_argument on an inconsistent problem.
void Validate(const Problem& p);

// Everything the outer loop works on, in the normalised frame.
struct Work {
  Frame frame;
  State state;
  StepData data;
  Weights weights;
};

Work Normalise(const Problem& p, const SolveOptions& o);
MeshPair Denormalise(const State& s, const Frame& f);
std::vector<FeatureLine> DenormaliseLines(const State& s, const Frame& f);
Marker DenormaliseMarker(Marker m, const Frame& f);
Marker NormaliseMarker(Marker m, const Frame& f);

// --- outer_steps.cc

// θ of an axis-aligned line: the nearest multiple of 90 degrees.
double NearestAxisTheta(double theta);

// Footpoints of every target point on M, and the outlier decision.
void UpdateFootpoints(const State& s, StepData& data, double phi, int threads);

// A surface point's position in M'.
Eigen::Vector2d FlatPoint(const State& s, const SurfacePoint& w);

// Total least squares line through each line's markers: the exact minimiser
// of E_line over (θ, offset) for the current M'.
void FitLines(State& s, const StepData& data);

// Feature line projection: p' onto its line, then the new face and
// barycentrics of the moved point in M'.
void ProjectMarkers(const State& s, StepData& data);

// --- terms.cc (EvaluateTerms is in residuals.h)

// Surrogate F (footpoints, normals and — under Gauss-Newton — lines fixed)
// at a state.
double SurrogateF(const State& s, const StepData& data, const Weights& w, int threads);

// --- lbfgs.cc

// L-BFGS on V, V' and the line parameters (footpoints held fixed): at most
// SolveOptions::lbfgs_iterations; returns whether F decreased (then `s`
// holds the new state). `iterations` gets the iterations run.
bool LbfgsStep(State& s, const StepData& data, const Weights& w, const SolveOptions& o,
               int* iterations);

}  // namespace docunfold::isometry::internal
