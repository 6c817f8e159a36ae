// optimize's flags: the solver's, declared once for every stage that runs it
// (isometry::DeclareSolveOptions), and optimize's own.
#include "common/option_table.h"
#include "stages/optimize/optimize.h"

namespace docunfold::optimize {

void DeclareOptions(OptionTable& table, OptimizeOptions* o) {
  table.Value("rounds", &o->rounds, "rounds of optimisation (subdivisions between them)");
  isometry::DeclareSolveOptions(table, &o->solve);
  table.Value("lambda-line", &o->solve.weights.line, 0.0, 1e9,
              "λ5, straightness of feature lines in M' (first round)");
  table.Value("lambda-ray", &o->solve.weights.ray, 0.0, 1e9,
              "λ6, feature points on their viewing rays (first round)");
  table.Value("feature-growth", &o->feature_weight_growth,
              "λ5 and λ6 are multiplied by this after each subdivision");
  table.Value(
      "converged-iterations", &o->converged_iterations, 1, 100,
      "a round stops at the outer iteration where |ΔF/F| is below its tolerance for this "
      "many times (in a row or not), in the rounds before --rises-from-round (1 = the paper: "
      "the first short step ends a round)");
  table.Value("first-rounds-tolerance", &o->first_rounds_tolerance, 0.0, 1.0,
              "in the rounds before --rises-from-round a round stops at |ΔF/F| below this "
              "instead of --tolerance (the coarse grids are cheap, and a fold they leave "
              "rounded stays rounded)");
  table.Value("max-rises", &o->max_rises, 0, 100000,
              "a round also stops once F has risen from one outer iteration to the next this "
              "many times (footpoints and markers re-decided make it oscillate); 0 = off");
  table.Value("rises-from-round", &o->rises_from_round, 0, 100000,
              "--max-rises applies from this round on (the first rounds are cheap)");
  table.Value("region-margin-px", &o->region_margin_px,
              "fit only points projecting inside the boundary contour grown by this many "
              "reference pixels");
  table.Value("side-outliers", &o->side_outliers, 0.0, 1.0,
              "take samples inside a real page side off it when farther than this fraction of "
              "M's diagonal, and 4 sigma of the side's scatter, from its line (0 = keep all)");
  table.Value("side-end-outliers", &o->side_end_outliers, 0.0, 1000.0,
              "in the last tenth at either end of a real side, take samples off it only when "
              "this many times farther from its line than a sample inside may be (0 = keep all)");
  table.Switch("feature-lines", &o->features,
               "text lines, rules and real page sides straightened in M' (off: an ablation)");
  table.Value("crease-step", &o->crease.step, 0.0, 10.0,
              "E_fair(M) is halved across a step in the reference photo's shading (a crease) "
              "of this much log-brightness per pixel, and falls off as its square above (0 = "
              "off: fair everywhere, as in the paper)");
  table.Value("crease-ink-px", &o->crease.ink_close_px, 1, 1000,
              "print narrower than this many pixels (of the reference photo read at most "
              "1600 px on its longer side) is closed away before the shading steps are read");
  table.Switch("mask-hull", &o->mask_hull,
               "hold page vertices that project outside another photo's page mask to that "
               "mask's outline (the photos' masks as a visual hull)");
  table.Value("hull-weight", &o->hull.weight, 0.001, 1e6,
              "weight of such a vertex in E_ray (a text sample's is 1)");
  table.Value("hull-outside-px", &o->hull.outside_px, 0.0, 1000.0,
              "a page vertex farther than this outside a photo's mask (its pixels) is held");
  table.Switch("boundary-only", &o->boundary_only,
               "only the real page sides as lines (an ablation)");
  table.Switch("projection", &o->solve.project_markers,
               "the paper's feature line projection (off: an ablation)");
  table.Value("marker-step", &o->marker_step_px, "sample spacing along segments (pixels)");
  table.Value("merge-gap", &o->grouping.gap,
              "segments merge when their closest ends are this close along the line "
              "(fraction of the M' diagonal)");
  table.Value("merge-offset", &o->grouping.offset,
              "... and this close across it (fraction of the M' diagonal)");
  table.Value("merge-straightness", &o->grouping.straightness,
              "largest h/w of a merged line's oriented box");
  table.Value("axis-tolerance", &o->grouping.axis_tolerance_deg,
              "lines kept within this many degrees of horizontal or vertical");
  table.Choice(
      "axis-lines", &o->axis_lines,
      {{"none", AxisLines::kNone}, {"features", AxisLines::kFeatures}, {"all", AxisLines::kAll}},
      "lines held along the axes of M': none (only straight, as in the paper), "
      "features (text and rules), all (and the real page sides)");
  table.Switch("upright-by-lines", &o->upright_by_lines,
               "turn M' before the first round where the segments run off its axes (off: keep "
               "init-mesh's upright M')");
  table.Value("upright-min-deg", &o->upright_min_deg, 0.0, 45.0,
              "turn M' when the segments run at least this many degrees off its axes");
}

}  // namespace docunfold::optimize
