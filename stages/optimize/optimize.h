// optimize: the joint isometric optimisation of M and M' with feature lines
// (paper §3-4, DESIGN §6): rounds of the inner loop of isometry::Solve,
// separated by Catmull-Clark subdivision, with markers recast, feature lines
// regrouped and markers projected onto their lines every outer iteration.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"
#include "common/isometry/isometry.h"
#include "common/page_files.h"
#include "stages/optimize/feature_lines.h"

namespace docunfold::optimize {

struct OptimizeOptions {
  int rounds = 4;                    // rounds of optimisation; rounds - 1 subdivisions between them
  isometry::Weights weights;         // λ1..λ6 of the first round (paper values)
  double feature_weight_growth = 4;  // λ5 and λ6 are multiplied by this per subdivision
  double relative_tolerance = 0.01;  // inner loop stops when |ΔF/F| < this (ε)
  // ... for the converged_iterations-th time (1 = the paper; see
  // isometry::SolveOptions::converged_iterations), in the rounds before
  // rises_from_round (below): they are cheap, and a round that stops on one
  // short step hands the next a page it has not finished fitting.
  int converged_iterations = 2;
  int max_outer_iterations = 100;  // ... or after this many outer iterations (Q)
  // ... or once F rose from one outer iteration to the next this often (0 =
  // off), in round rises_from_round and later. With markers re-decided every
  // iteration F can oscillate without settling in the fine rounds, where an
  // iteration costs ~0.4 s: set04 took 21 iterations in its last round (12 s
  // in all) and 4.5 s in all from another start. The first rounds are cheap
  // and may need many iterations (set02's first: 35, after a rise at the 4th).
  int max_rises = 3;
  int rises_from_round = 2;
  double outlier_distance = 0.06;  // φ, fraction of the model size
  // Only points projecting into the document region of the reference view
  // (boundary contour grown by this many pixels) are fitted, as in
  // init-mesh; points of the table beside the page are within φ of M's edge
  // and would pull it outward.
  double region_margin_px = 4;
  double iso_edges = 0;  // isometry::SolveOptions::iso_edges
  // DropSideOutliers' tolerance (fraction of M's diagonal; 0 keeps every
  // marker). On set05 a fold's notch in the left side's outline, 30 px off
  // the page's edge in flat.png, was held straight with the side; two front
  // ends, 12 sets: set05 +0.009 and +0.005, the sample mean -0.000 and +0.004,
  // the realistic sets' +0.004 and -0.003 (README, "Choices we measured").
  double side_outliers = 0.005;
  // DropSideOutliers' end_factor (0 keeps every marker in a side's last
  // tenths). r03's standing flap: the bottom side's first samples landed
  // 5-18 % of M's diagonal off its line, somewhere else each iteration, so F
  // jumped (the line term x20) and rounds 0 and 1 ran 61 and 44 iterations.
  // 4 against 0 on three benchmark front ends: r03 0.691 -> 0.719 (11 ->
  // 5.6 s), set04 +0.010, set08 -0.003 on one, all 12 identical on another,
  // r03 +0.004 on the third; 3 took a curved end of set04's and set08's
  // sides off (-0.010, -0.011) (README, "Choices we measured").
  double side_end_outliers = 4;
  isometry::Method method = isometry::Method::kGaussNewton;
  isometry::LinearSolver linear_solver = isometry::LinearSolver::kAuto;
  bool features = true;        // false: no feature lines at all (--no-features)
  bool boundary_only = false;  // only the real boundary sides (--boundary-only)
  bool project = true;         // feature line projection (paper §"Feature line projection")
  // Which lines run exactly along the axes of the upright M' (kNone: only
  // straight, as in the paper). A page is a rectangle: with only straight
  // sides, M' kept one of set04's sides 1.5 degrees off the others (M is
  // least certain at the page edge) and the crop cut into the page. kAll
  // against kNone, 12 sets on three sfm runs: mean MS-SSIM of the samples
  // +0.017, +0.015, +0.030 (set04 +0.16 each time, r02 +0.10, r01 +0.05;
  // worst single change set02 -0.022 and set07 -0.011).
  AxisLines axis_lines = AxisLines::kAll;
  double marker_step_px = 4;  // sample spacing along segments, reference pixels
  // Turn M' before the first round when the detected segments (text rows,
  // rules) run at least upright_min_deg off its axes: at least
  // upright_min_segments of them, upright_min_share of their length within
  // 3 degrees of one direction. Measured on the 12 benchmark sets: set08
  // (a fold taken for the top side) 31 deg off with 59-150 segments, 78-98 %
  // agreeing; set07's curled receipt 6-10 deg off with 12-13 segments, 62-69 %
  // agreeing, where turning changed nothing (render deskews by the sides);
  // every other set within 1.2 deg.
  bool upright_by_lines = true;
  double upright_min_deg = 2;
  int upright_min_segments = 20;
  double upright_min_share = 0.5;
  CastOptions cast;
  GroupingOptions grouping;
  int threads = 2;
};

struct OptimizeInputs {
  MeshPair init;                                     // 40_init/
  PinholeCamera reference;                           // reference camera (world = its frame)
  std::vector<Eigen::Vector3d> points;               // points to fit (sfm's or densify's)
  std::vector<std::array<uint8_t, 3>> point_colors;  // empty, or one per point
  Boundary boundary;
  FeatureFile features;
};

// A feature line at the end of a round, for lines.json.
struct LineRecord {
  std::string kind;  // text, edge, boundary
  int side = -1;     // boundary side (0 top, 1 right, 2 bottom, 3 left)
  int segments = 0;
  isometry::FeatureLine line;           // n·p' = offset in M'
  std::vector<Eigen::Vector2d> pixels;  // its markers in the reference image
  std::vector<Eigen::Vector2d> flat;    // and in M'
};

struct RoundResult {
  int round = 0;
  MeshPair meshes;
  isometry::Weights weights;
  isometry::SolveReport report;
  std::vector<LineRecord> lines;
  // Page-side markers DropSideOutliers took off their side in the round's
  // last outer iteration.
  int side_markers_dropped = 0;
  double start_seconds = 0;  // since optimize started
};

struct OptimizeResult {
  MeshPair meshes;  // final M and M'
  std::vector<RoundResult> rounds;
  std::vector<int> region_points;  // indices of the SfM points in the document region
  AxisDirection line_direction;    // of the segments in M' before the first round
  // The reader's down in the final M' (unit), from the feature file's
  // text_down through an affine fit of the final lines' pixels to M'.
  std::optional<Eigen::Vector2d> text_down_flat;
  double upright_turn_deg = 0;  // M' turned by this before the first round
  std::vector<bool> inliers;    // per region point, after the last round
  int segments = 0;             // feature segments given (text + edge)
  int segments_off_page = 0;    // of those, dropped: their samples miss M
  int boundary_lines = 0;       // real boundary sides used
  double seconds = 0;
};

// Throws InputError when the inputs do not fit together (features for
// another image size, say) and std::runtime_error when the solver fails.
OptimizeResult Run(const OptimizeInputs& inputs, const OptimizeOptions& options);

}  // namespace docunfold::optimize
