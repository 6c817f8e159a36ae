// optimize: the joint isometric optimisation of M and M' with feature lines.
#include <cstdio>

#include "common/cli.h"
#include "stages/optimize/optimize.h"
#include "stages/optimize/optimize_io.h"

int main(int argc, char** argv) {
  using namespace docunfold;
  optimize::OptimizeOptions o;
  optimize::InputPaths paths;
  fs::path out;
  std::string solver = "gn", linear = "auto";
  bool no_features = false, no_projection = false, no_scene = false;
  CLI::App app{
      "optimize: jointly optimises the 3D page M and its flat twin M' under the isometry "
      "constraint, fitted to the SfM points, with text lines, table rules and the real page "
      "sides straightened in M' (Luo & Bo). Writes <out>/mesh3d.ply, mesh2d.ply, lines.json, "
      "log.json, scene.glb and round0/ ... roundK/."};
  app.add_option("--sfm", paths.sfm, "10_sfm/ (cameras.json, points.ply, reference.png)")
      ->required();
  app.add_option("--boundary", paths.boundary, "20_boundary/ or its boundary.json")->required();
  app.add_option("--features", paths.features, "feature segments (docunfold.features)")->required();
  app.add_option("--init", paths.init, "40_init/ (mesh3d.ply, mesh2d.ply)")->required();
  app.add_option(
      "--points", paths.points,
      "3D points to fit (default: <sfm>/points.ply; densify writes 25_points/points.ply)");
  app.add_option("--out", out, "output folder, e.g. 50_optimize")->required();
  app.add_option("--rounds", o.rounds, "rounds of optimisation (subdivisions between them)")
      ->capture_default_str();
  app.add_option("--lambda-iso", o.weights.iso, "λ1, isometry")->capture_default_str();
  app.add_option("--lambda-dist", o.weights.dist, "λ2, distance to the points")
      ->capture_default_str();
  app.add_option("--lambda-fair3d", o.weights.fair3d, "λ3, fairness of M")->capture_default_str();
  app.add_option("--lambda-fair2d", o.weights.fair2d, "λ4, fairness of M'")->capture_default_str();
  app.add_option("--lambda-line", o.weights.line, "λ5, straightness of feature lines in M'")
      ->capture_default_str();
  app.add_option("--lambda-ray", o.weights.ray, "λ6, feature points on their viewing rays")
      ->capture_default_str();
  app.add_option("--feature-growth", o.feature_weight_growth,
                 "λ5 and λ6 are multiplied by this after each subdivision")
      ->capture_default_str();
  app.add_option("--tolerance", o.relative_tolerance, "inner loop stops when |ΔF/F| < this")
      ->capture_default_str();
  app.add_option("--converged-iterations", o.converged_iterations,
                 "... for this many times (in a row or not), in the rounds before "
                 "--rises-from-round (1 = the paper: the first short step ends a round)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_option("--max-rises", o.max_rises,
                 "inner loop also stops once F has risen from one outer iteration to the next this "
                 "many times (footpoints and markers re-decided make it oscillate); 0 = off")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  app.add_option("--rises-from-round", o.rises_from_round,
                 "--max-rises applies from this round on (the first rounds are cheap)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  app.add_option("--max-iterations", o.max_outer_iterations, "outer iterations per round at most")
      ->capture_default_str();
  app.add_option("--outlier-distance", o.outlier_distance,
                 "points farther from M than this fraction of the model size are ignored")
      ->capture_default_str();
  app.add_option("--region-margin-px", o.region_margin_px,
                 "fit only points projecting inside the boundary contour grown by this many "
                 "reference pixels")
      ->capture_default_str();
  AddIsoEdgesOption(app, &o.iso_edges);
  app.add_option("--side-outliers", o.side_outliers,
                 "take samples inside a real page side off it when farther "
                 "than this fraction of M's diagonal, and 4 sigma of the "
                 "side's scatter, from its line (0 = keep all)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--side-end-outliers", o.side_end_outliers,
                 "in the last tenth at either end of a real side, take samples off it "
                 "only when this many times farther from its line than a sample inside may "
                 "be (0 = keep all)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--solver", solver, "gn (Gauss-Newton/LM, sparse Cholesky) or lbfgs")
      ->capture_default_str();
  app.add_option("--linear-solver", linear,
                 "Gauss-Newton's normal equations: auto (Cholesky on small grids, conjugate "
                 "gradients on large), direct or cg")
      ->capture_default_str();
  app.add_flag("--no-features", no_features, "no feature lines at all (ablation)");
  app.add_flag("--boundary-only", o.boundary_only, "only the real page sides as lines (ablation)");
  app.add_flag("--no-projection", no_projection, "without feature line projection (ablation)");
  app.add_option("--marker-step", o.marker_step_px, "sample spacing along segments, pixels")
      ->capture_default_str();
  app.add_option("--merge-gap", o.grouping.gap,
                 "segments merge when their closest ends are this close along the line "
                 "(fraction of the M' diagonal)")
      ->capture_default_str();
  app.add_option("--merge-offset", o.grouping.offset,
                 "... and this close across it (fraction of the M' diagonal)")
      ->capture_default_str();
  app.add_option("--straightness", o.grouping.straightness,
                 "largest h/w of a merged line's oriented box")
      ->capture_default_str();
  app.add_option("--axis-tolerance", o.grouping.axis_tolerance_deg,
                 "lines kept within this many degrees of horizontal or vertical")
      ->capture_default_str();
  std::string axis_lines = o.axis_lines == optimize::AxisLines::kNone       ? "none"
                           : o.axis_lines == optimize::AxisLines::kFeatures ? "features"
                                                                            : "all";
  app.add_option("--axis-lines", axis_lines,
                 "lines held along the axes of M': none (only straight, as in the paper), "
                 "features (text and rules), all (and the real page sides)")
      ->capture_default_str()
      ->check(CLI::IsMember({"none", "features", "all"}));
  bool no_upright = false;
  app.add_flag("--no-upright-by-lines", no_upright,
               "keep init-mesh's upright M' even where the segments run off its axes");
  app.add_option("--upright-min-deg", o.upright_min_deg,
                 "turn M' when the segments run at least this many degrees off its axes")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 45.0));
  app.add_option("--threads", o.threads,
                 "solver threads at most; each outer iteration runs fewer "
                 "while other processes keep the cores busy")
      ->capture_default_str();
  app.add_flag("--no-scene", no_scene, "do not write scene.glb");
  return RunStage("optimize", app, argc, argv, [&] {
    if (solver == "gn") {
      o.method = isometry::Method::kGaussNewton;
    } else if (solver == "lbfgs") {
      o.method = isometry::Method::kLbfgs;
    } else {
      throw UsageError("--solver must be gn or lbfgs, not '" + solver + "'");
    }
    if (linear == "auto") {
      o.linear_solver = isometry::LinearSolver::kAuto;
    } else if (linear == "direct") {
      o.linear_solver = isometry::LinearSolver::kDirect;
    } else if (linear == "cg") {
      o.linear_solver = isometry::LinearSolver::kConjugateGradient;
    } else {
      throw UsageError("--linear-solver must be auto, direct or cg, not '" + linear + "'");
    }
    o.features = !no_features;
    o.project = !no_projection;
    o.upright_by_lines = !no_upright;
    o.axis_lines = axis_lines == "none"       ? optimize::AxisLines::kNone
                   : axis_lines == "features" ? optimize::AxisLines::kFeatures
                                              : optimize::AxisLines::kAll;
    const Json options_json = {{"rounds", o.rounds},
                               {"solver", solver},
                               {"linear_solver", linear},
                               {"lambda",
                                {o.weights.iso, o.weights.dist, o.weights.fair3d, o.weights.fair2d,
                                 o.weights.line, o.weights.ray}},
                               {"feature_growth", o.feature_weight_growth},
                               {"tolerance", o.relative_tolerance},
                               {"converged_iterations", o.converged_iterations},
                               {"max_iterations", o.max_outer_iterations},
                               {"max_rises", o.max_rises},
                               {"rises_from_round", o.rises_from_round},
                               {"outlier_distance", o.outlier_distance},
                               {"region_margin_px", o.region_margin_px},
                               {"iso_edges", o.iso_edges},
                               {"side_outliers", o.side_outliers},
                               {"side_end_outliers", o.side_end_outliers},
                               {"features", o.features},
                               {"boundary_only", o.boundary_only},
                               {"projection", o.project},
                               {"marker_step", o.marker_step_px},
                               {"merge_gap", o.grouping.gap},
                               {"merge_offset", o.grouping.offset},
                               {"straightness", o.grouping.straightness},
                               {"axis_tolerance", o.grouping.axis_tolerance_deg},
                               {"upright_by_lines", o.upright_by_lines},
                               {"axis_lines", axis_lines},
                               {"upright_min_deg", o.upright_min_deg}};
    const optimize::OptimizeInputs in = optimize::ReadInputs(paths);
    const optimize::OptimizeResult r = optimize::Run(in, o);
    optimize::OutputOptions output;
    output.scene = !no_scene;
    optimize::WriteOutputs(out, paths, in, r, options_json, output);
    char buf[200];
    std::snprintf(buf, sizeof buf, "wrote %s: %dx%d grid after %zu rounds, %zu lines, %.1f s",
                  out.c_str(), r.meshes.grid.nx, r.meshes.grid.ny, r.rounds.size(),
                  r.rounds.back().lines.size(), r.seconds);
    Log(buf);
  });
}
