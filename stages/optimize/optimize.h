// optimize: the joint isometric optimisation of M and M' with feature lines
// (the paper's "Document image rectification using isometric mapping" and
// "Feature line generation"): rounds of the inner loop of isometry::Solve,
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
#include "common/option_table_fwd.h"
#include "common/page_files.h"
#include "stages/optimize/crease_evidence.h"
#include "stages/optimize/feature_lines.h"
#include "stages/optimize/mask_hull.h"

namespace docunfold::optimize {

struct OptimizeOptions {
  // The solver's settings for every round (isometry::DeclareSolveOptions):
  // λ1..λ6 of the first round (the paper's), φ, the method and its stopping
  // rule, threads. Each round hands the solver a copy with its own λ5, λ6,
  // converged_iterations and max_rises (below) and the marker callback.
  // Feature line projection (the paper's) is on.
  isometry::SolveOptions solve = [] {
    isometry::SolveOptions o;
    o.project_markers = true;
    return o;
  }();
  int rounds = 4;                    // rounds of optimisation; rounds - 1 subdivisions between them
  double feature_weight_growth = 4;  // λ5 and λ6 are multiplied by this per subdivision
  // A round stops at the converged_iterations-th outer iteration with
  // |ΔF/F| < ε (1 = the paper; see isometry::SolveOptions::
  // converged_iterations), in the rounds before rises_from_round: they are
  // cheap, and a round that stops on one short step hands the next a page it
  // has not finished fitting. From rises_from_round on, 1.
  int converged_iterations = 2;
  // ε of those first rounds (later rounds: solve.relative_tolerance, the
  // paper's 0.01). Past 1 % a round is still crawling: with footpoints and
  // markers re-decided each outer iteration F keeps falling by 0.1-0.5 % an
  // iteration as a rounded fold unrounds, and what the coarse grids leave
  // rounded the fine rounds do not undo. See docs/decisions/optimize.md, "The first
  // rounds run to 1e-4".
  double first_rounds_tolerance = 1e-4;
  // From round rises_from_round on, a round also stops once F rose from one
  // outer iteration to the next this often (0 = off): with markers re-decided
  // every iteration F can oscillate without settling in the fine rounds,
  // where an iteration is expensive; the first rounds are cheap and may need
  // many iterations. See docs/decisions/optimize.md, "Stopping on rises".
  int max_rises = 3;
  int rises_from_round = 2;
  // Only points projecting into the document region of the reference view
  // (boundary contour grown by this many pixels) are fitted, as in
  // init-mesh; points of the table beside the page are within φ of M's edge
  // and would pull it outward.
  double region_margin_px = 4;
  // DropSideOutliers' tolerance (fraction of M's diagonal; 0 keeps every
  // marker): a fold's notch in a side's outline is not held straight with
  // the side. See docs/decisions/optimize.md, "A notch in a page side".
  double side_outliers = 0.005;
  // DropSideOutliers' end_factor (0 keeps every marker in a side's last
  // tenths): a sample whose ray grazes M's border and lands elsewhere each
  // iteration makes F jump. See docs/decisions/optimize.md, "A sample at a
  // side's end".
  double side_end_outliers = 4;
  CreaseOptions crease;
  bool features = true;        // false: no feature lines at all (--no-feature-lines)
  bool boundary_only = false;  // only the real boundary sides (--boundary-only)
  // Which lines run exactly along the axes of the upright M' (kNone: only
  // straight, as in the paper). A page is a rectangle: with only straight
  // sides M' can keep a side a little off the others (M is least certain at
  // the page edge) and the crop cuts into the page. See
  // docs/decisions/optimize.md, "Every line along an axis of M'".
  AxisLines axis_lines = AxisLines::kAll;
  double marker_step_px = 4;  // sample spacing along segments, reference pixels
  // Turn M' before the first round when the detected segments (text rows,
  // rules) run at least upright_min_deg off its axes: at least
  // upright_min_segments of them, upright_min_share of their length within
  // 3 degrees of one direction (a fold taken for a side turned M'). See
  // docs/decisions/optimize.md, "M' turned upright by the lines".
  bool upright_by_lines = true;
  double upright_min_deg = 2;
  int upright_min_segments = 20;
  double upright_min_share = 0.5;
  CastOptions cast;
  GroupingOptions grouping;
  // The other photos' page masks as a visual hull (mask_hull.h): page
  // vertices projecting outside one get hull markers, re-decided every outer
  // iteration with the other markers. See docs/decisions/optimize.md, "The
  // other photos' masks as a visual hull".
  bool mask_hull = true;
  HullOptions hull;
};

// Declares optimize's flags into `table`, bound to `options`' fields: the
// solver's (isometry::DeclareSolveOptions) and optimize's own.
void DeclareOptions(OptionTable& table, OptimizeOptions* options);

// What round `round` (0 first) hands the solver: options.solve with the
// round's weights (λ5 and λ6 grown per subdivision by the caller) and
// stopping rule (converged_iterations before rises_from_round, max_rises
// from it on).
isometry::SolveOptions RoundSolveOptions(const OptimizeOptions& options, int round,
                                         const isometry::Weights& weights);

struct OptimizeInputs {
  MeshPair init;                                     // 40_init/
  PinholeCamera reference;                           // reference camera (world = its frame)
  std::vector<Eigen::Vector3d> points;               // points to fit (sfm's or densify's)
  std::vector<std::array<uint8_t, 3>> point_colors;  // empty, or one per point
  Boundary boundary;
  FeatureFile features;
  std::vector<ViewPage> other_views;  // 20_boundary/views/*/mask.png
  cv::Mat reference_image;            // <sfm>/reference.png (empty: not read)
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
  int hull_markers = 0;      // in the round's last outer iteration
  int crease_triplets = 0;   // E_fair(M) triplets spared across a shading step
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
  double upright_turn_deg = 0;            // M' turned by this before the first round
  std::vector<bool> inliers;              // per region point, after the last round
  int segments = 0;                       // feature segments given (text + edge)
  int segments_off_page = 0;              // of those, dropped: their samples miss M
  int boundary_lines = 0;                 // real boundary sides used
  std::vector<HullViewCheck> hull_views;  // the other photos' masks (mask_hull)
  double seconds = 0;
};

// Throws InputError when the inputs do not fit together (features for
// another image size, say) and std::runtime_error when the solver fails.
OptimizeResult Run(const OptimizeInputs& inputs, const OptimizeOptions& options);

}  // namespace docunfold::optimize
