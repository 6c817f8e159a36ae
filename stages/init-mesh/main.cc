// init-mesh --sfm 10_sfm --boundary 20_boundary --out 40_init [options]
// Writes mesh3d.ply (M), mesh2d.ply (M') and init.json (see init_mesh.h).
#include <chrono>
#include <map>
#include <regex>

#include "common/cli.h"
#include "stages/init-mesh/init_mesh.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CLI::App app{
      "Initial meshes of the page: a quad grid on the document region of the reference "
      "image (Coons patch of the boundary sides), lifted to 3D by the depths of the SfM "
      "points, unfolded to the plane and refined by the joint isometric optimisation "
      "without feature lines; M' is turned upright by the page border."};
  fs::path sfm_dir, boundary_dir, out_dir, points_path;
  init_mesh::Options o;
  std::string grid = "20x30", method = "gn", iso = "strain";
  bool no_upright = false, verbose = false;
  app.add_option("--sfm", sfm_dir, "sfm output: cameras.json, points.ply, reference.png")
      ->required();
  app.add_option("--boundary", boundary_dir, "segment-boundary output: boundary.json, mask.png")
      ->required();
  app.add_option(
      "--points", points_path,
      "3D points to fit (default: <sfm>/points.ply; densify writes 25_points/points.ply)");
  app.add_option("--out", out_dir, "output directory (mesh3d.ply, mesh2d.ply, init.json)")
      ->required();
  app.add_option("--grid", grid, "quads across the page's short side x along its long side")
      ->capture_default_str();
  app.add_option("--k", o.depth_neighbours, "nearest SfM points per grid vertex for its depth")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--rbf-scale-px", o.rbf_scale_px,
                 "pixel distance unit of the depth weights 1/(1+r^2); 0 = median spacing of "
                 "the projected points, 1 = plain pixels as in the paper")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--depth-model", o.depth_model,
                 "planar: fit 1/depth as an affine function of the pixel to the nearest "
                 "--planar-k points (continues each panel's plane over blank paper); average: "
                 "the weighted mean depth of the --k nearest (the paper)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, DepthModel>{{"planar", DepthModel::kPlanar},
                                            {"average", DepthModel::kAverage}},
          CLI::ignore_case))
      ->default_str("planar");
  app.add_option("--planar-k", o.planar_neighbours, "nearest SfM points in each planar depth fit")
      ->capture_default_str()
      ->check(CLI::Range(6, 256));
  app.add_option("--planar-guard", o.planar_guard,
                 "where the planar fits to the 2 x --planar-k and the --planar-k nearest "
                 "points disagree by more than this fraction of the depth, take the wider "
                 "one; 0 = off")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--depth-outlier", o.depth_outlier,
                 "points off the median depth of their image neighbours by more than this "
                 "fraction are not used for the depth")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--mask-margin-px", o.mask_margin_px,
                 "points this close outside mask.png still count as on the page")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--min-points", o.min_points, "fewer SfM points on the page is bad input (exit 3)")
      ->capture_default_str()
      ->check(CLI::Range(4, 1000000));
  app.add_option("--min-points-per-ninth", o.min_points_per_ninth,
                 "a ninth of the page (3x3 parts of the grid) with fewer SfM points has none")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  app.add_option("--min-covered-ninths", o.min_covered_ninths,
                 "points in fewer of the page's 9 parts are bad input (exit 3); an empty "
                 "third is a warning")
      ->capture_default_str()
      ->check(CLI::Range(0, 9));
  app.add_option("--outlier-distance", o.refine.outlier_distance,
                 "phi: points farther from M than this fraction of the model size are "
                 "ignored (re-decided every iteration)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--lambda-iso", o.refine.weights.iso, "lambda1, isometry")->capture_default_str();
  app.add_option("--lambda-dist", o.refine.weights.dist, "lambda2, point fitting")
      ->capture_default_str();
  app.add_option("--lambda-fair3d", o.refine.weights.fair3d, "lambda3, fairness of M")
      ->capture_default_str();
  app.add_option("--lambda-fair2d", o.refine.weights.fair2d, "lambda4, fairness of M'")
      ->capture_default_str();
  app.add_option("--iso-normalization", iso,
                 "strain: E_iso as mean squared strain (resolution independent); raw: the "
                 "paper's sum of squared c_iso")
      ->capture_default_str()
      ->check(CLI::IsMember({"strain", "raw"}));
  AddIsoEdgesOption(app, &o.refine.iso_edges);
  app.add_option("--outline-hold", o.outline_hold,
                 "weight of the term holding M's border to the page outline in the reference "
                 "image (sliding along it); 0 = off")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--outline-hold-max-angle", o.outline_hold_max_angle_deg,
                 "border vertices where M is seen more than this far off its normal (degrees) are "
                 "not held: the outline there is likely a silhouette")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 90.0));
  app.add_option("--outline-hold-support", o.outline_hold_support,
                 "border vertices farther than this from every point (fraction of the model "
                 "size) are not held: M's shape there is a guess")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--method", method, "gn: Gauss-Newton/Levenberg-Marquardt; lbfgs: L-BFGS")
      ->capture_default_str()
      ->check(CLI::IsMember({"gn", "lbfgs"}));
  app.add_option("--max-iterations", o.refine.max_outer_iterations,
                 "outer iterations of the refinement (Q)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  app.add_option("--converged-max-damping", o.refine.converged_max_damping,
                 "|dF/F| below --tolerance does not stop the refinement while the "
                 "Levenberg-Marquardt damping is above this (its steps are then short, not "
                 "converged); 0 = it always stops")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--tolerance", o.refine.relative_tolerance,
                 "stop when |dF/F| between outer iterations is below this (epsilon)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--threads", o.refine.num_threads,
                 "solver threads at most; each outer iteration runs fewer "
                 "while other processes keep the cores busy")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_flag("--no-upright", no_upright, "keep M' as unfolded (do not turn it upright)");
  bool no_regrid = false;
  app.add_flag("--no-regrid", no_regrid,
               "keep the image-space grid (do not re-grid uniformly on the page after unfolding)");
  bool no_outline_prior = false;
  app.add_flag("--no-outline-prior", no_outline_prior,
               "lift the grid by the points alone (by default the page's outline in 3D, from "
               "densify's outline points, shapes blank paper where the points agree with it)");
  app.add_option("--outline-prior-agreement", o.outline_prior.agreement,
                 "the outline's surface counts where the nearby points' depths differ from it "
                 "by about this fraction or less (weight exp(-(e/a)^2))")
      ->capture_default_str()
      ->check(CLI::Range(1e-6, 1.0));
  app.add_flag("--verbose", verbose, "log every outer iteration of the refinement");

  return RunStage("init-mesh", app, argc, argv, [&] {
    const auto start = std::chrono::steady_clock::now();
    std::smatch match;
    if (!std::regex_match(grid, match, std::regex(R"((\d+)x(\d+))")))
      throw UsageError("--grid: expected AxB (quads across the short side x the long side), got '" +
                       grid + "'");
    o.grid_short = std::stoi(match[1]);
    o.grid_long = std::stoi(match[2]);
    if (o.grid_short < 1 || o.grid_long < 1 || o.grid_short > 2000 || o.grid_long > 2000)
      throw UsageError("--grid: between 1 and 2000 quads per side");
    o.upright = !no_upright;
    o.regrid_on_page = !no_regrid;
    o.outline_prior.enabled = !no_outline_prior;
    o.refine.method = method == "gn" ? isometry::Method::kGaussNewton : isometry::Method::kLbfgs;
    o.refine.iso_normalization =
        iso == "strain" ? isometry::IsoNormalization::kStrain : isometry::IsoNormalization::kRaw;

    const init_mesh::Inputs inputs = init_mesh::ReadInputs(sfm_dir, boundary_dir, points_path);
    const double read_seconds = SecondsSince(start);
    const init_mesh::Result result = init_mesh::Run(inputs, o);
    for (const std::string& w : result.warnings) Log("warning: " + w);
    if (result.outline_prior.used)
      Log("outline prior: " + std::to_string(result.outline_prior.measured_sides) +
          " sides measured, weight " +
          std::to_string(result.outline_prior.mean_weight).substr(0, 4) + " on average");
    else if (o.outline_prior.enabled)
      Log("outline prior not used: " + result.outline_prior.note);
    if (verbose)
      for (const auto& it : result.refine.iterations)
        Log("refine " + std::to_string(it.iteration) + ": F " + std::to_string(it.F) + " (iso " +
            std::to_string(it.terms.iso) + ", dist " + std::to_string(it.terms.dist) + ", fair3d " +
            std::to_string(it.terms.fair3d) + ", fair2d " + std::to_string(it.terms.fair2d) +
            "), inliers " + std::to_string(it.inliers) + ", damping " + std::to_string(it.damping) +
            (it.step_accepted ? "" : ", no step"));
    init_mesh::WriteOutputs(out_dir, inputs, result, o, read_seconds);
    const auto& its = result.refine.iterations;
    Log(std::to_string(result.meshes.grid.nx - 1) + "x" +
        std::to_string(result.meshes.grid.ny - 1) + " quads (" + result.grid_source + "), " +
        std::to_string(result.inliers) + "/" + std::to_string(result.points_in_region) +
        " points inliers, refined in " + std::to_string(its.size()) + " iterations (F " +
        std::to_string(its.front().F) + " -> " + std::to_string(its.back().F) +
        "), isometry error " + std::to_string(100 * result.isometry_error_mean).substr(0, 5) +
        " %, " + std::to_string(SecondsSince(start)).substr(0, 4) + " s");
  });
}
