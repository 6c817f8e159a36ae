// init-mesh: the initial pair of meshes M (3D page) and M' (its flat twin)
// from the SfM points and the page boundary in the reference image (the
// paper's "Initialization"):
//  1. a quad grid M^r on the page in the reference image: a Coons patch of
//     the four boundary sides (resampled by arc length on the page), else a
//     grid over the mask's bounding box;
//  2. the depth of each grid vertex from the SfM points projected into the
//     image (points inside the page region), RBF-weighted: a planar fit of
//     inverse depth to the nearest (default) or the paper's mean depth of
//     the k nearest; lifted to 3D through the reference camera;
//  3. M unfolded to the plane (as-rigid-as-possible) for M';
//  4. both refined by the joint optimisation with the feature terms off
//     (isometry, point fitting, fairness, progressive outlier filtering);
//  5. where more of the page's points (seen on the page by every photo that
//     frames them) lie off M than the reference outline can explain, M and
//     M' rebuilt from those points alone (page_from_points.h) and refined;
//  6. an end of M folded up on a grid line where the other photos' page
//     masks show it standing (end_fold.h);
//  7. M' turned upright by the oriented bounding box of the real boundary
//     sides (of the whole mesh when no side is real): top side at small y.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/depth_field.h"
#include "common/grid_mesh.h"
#include "common/isometry/isometry.h"
#include "common/json_io.h"
#include "common/option_table_fwd.h"
#include "common/page_files.h"
#include "common/point_source.h"
#include "stages/init-mesh/end_fold.h"
#include "stages/init-mesh/outline_prior.h"
#include "stages/init-mesh/page_from_points.h"

namespace docunfold::init_mesh {

namespace fs = std::filesystem;

// Quads of the grid M^r: `short_side` across the page's shorter side,
// `long_side` along its longer side (sides measured on the page in 3D).
struct GridQuads {
  int short_side = 20;
  int long_side = 30;
};

struct Options {
  GridQuads grid;
  // Depth of a grid vertex: the k nearest projected SfM points, weighted by
  // φ(r) = 1/(1+r²) with r = pixel distance / rbf_scale_px. 0 = automatic:
  // the median spacing of the projected points, so the weights do not depend
  // on the image resolution (1 gives the paper's plain pixels).
  int depth_neighbours = 3;
  double rbf_scale_px = 0;
  // kAverage is the paper's weighted mean of those k depths. kPlanar fits
  // 1/depth as an affine function of the pixel to the `planar_neighbours`
  // nearest (same weights): exact on a plane, so blank margins and gaps
  // continue their panel's plane instead of taking the nearest text's depth.
  DepthModel depth_model = DepthModel::kPlanar;
  int planar_neighbours = 16;
  // Points whose depth differs by more than this fraction from the median
  // depth of their 8 nearest image neighbours are not used for the depth
  // (they still take part in the refinement, where φ decides).
  double depth_outlier = 0.05;
  // Points projecting at most this far outside mask.png count as inside.
  double mask_margin_px = 4;
  // Bad input (exit 3): fewer points than this in the document region, or
  // points (at least min_points_per_ninth) in fewer than min_covered_ninths
  // of the page's 3x3 parts. A third of the page without points is a
  // warning: fairness and isometry carry the mesh over it (a panel of a fold
  // that only one other photo sees has none; see docs/decisions/init-mesh.md,
  // "Points on part of the page").
  int min_points = 30;
  int min_points_per_ninth = 1;
  int min_covered_ninths = 5;
  // After unfolding, re-grid uniformly on the page (a Coons patch of the
  // border of M'), so that M' starts fair.
  bool regrid_on_page = true;
  // The refinement: the joint optimisation with λ5 = λ6 = 0 (forced), with
  // init-mesh's own defaults:
  //  - λ4 (fairness of M') 0.01 instead of the paper's 0.1: on a page cut by
  //    the image border the visible region is no quadrilateral on the page,
  //    so its grid lines are curves in M' that a stronger fairness fights;
  //  - edge-length rows join the paper's diagonal rows in E_iso (iso_edges
  //    0.5): with diagonals only, quads seen at a grazing angle twist out of
  //    their planes (optimize keeps the paper's diagonals);
  //  - |ΔF/F| below the tolerance does not stop the refinement while the
  //    Levenberg-Marquardt damping is above 0.01 (its steps are then short,
  //    not converged);
  //  - exact steps (CHOLMOD): its grid is coarse, and inexact ones left the
  //    receipts' blank paper unsettled.
  // See docs/decisions/init-mesh.md, "The refinement's defaults".
  isometry::SolveOptions refine = [] {
    isometry::SolveOptions o;
    o.weights.fair2d = 0.01;
    o.iso_edges = 0.5;
    o.converged_max_damping = 0.01;
    o.linear_solver = isometry::LinearSolver::kDirect;
    return o;
  }();
  bool upright = true;
  // The depth of blank paper from the page's outline in 3D (densify's
  // outline points, PointSource::kOutline in points.ply): outline_prior.h.
  OutlinePriorOptions outline_prior;
  // A page the reference outline does not bound, rebuilt from the points of
  // every photo: page_from_points.h.
  PageFromPointsOptions page_from_points;
  // An end folded up steeply, from the other photos' masks: end_fold.h.
  EndFoldOptions end_fold;
  bool verbose = false;  // log every outer iteration of the refinement
};

// Declares init-mesh's flags, bound to `options`' fields (the solver's
// through isometry::DeclareSolveOptions).
void DeclareOptions(OptionTable& table, Options* options);

struct Inputs {
  PinholeCamera reference;              // the reference view
  std::vector<Eigen::Vector3d> points;  // SfM points, world frame
  // Per point: points.ply's `source`; empty when the file has none (sfm's
  // own cloud).
  std::vector<PointSource> point_sources;
  Boundary boundary;
  cv::Mat1b mask;            // 255 inside the page
  fs::path reference_image;  // 10_sfm/reference.png
  // The other photos' pages (20_boundary/views/<photo>/mask.png where
  // segment-boundary found one); empty for a work folder without them.
  std::vector<ViewPage> other_photos;
};

// Reads and validates 10_sfm/{cameras.json, points.ply, reference.png} and
// 20_boundary/{boundary.json, mask.png, views/*/mask.png}; throws InputError naming the file.
// `points_path` empty: sfm_dir/points.ply.
Inputs ReadInputs(const fs::path& sfm_dir, const fs::path& boundary_dir,
                  const fs::path& points_path = {});

struct Timings {
  double grid = 0, depth = 0, unfold = 0, refine = 0, page = 0, ends = 0, upright = 0, total = 0;
};

struct Result {
  MeshPair meshes;
  // "coons" (boundary sides), "mask_bbox" or "page_points" (rebuilt from
  // the page's points)
  std::string grid_source;
  std::vector<std::string> warnings;
  int points_total = 0;
  int points_in_region = 0;
  int points_for_depth = 0;
  int inliers = 0;
  double rbf_scale_px = 0;
  int unfold_iterations = 0;
  isometry::SolveReport refine;
  double upright_rotation_deg = 0;
  std::string upright_from;        // "real sides: top, left, ..." or "whole mesh"
  double isometry_error_mean = 0;  // mean relative edge-length difference of (M, M')
  double isometry_error_max = 0;
  double mean_inlier_distance = 0;  // of the SfM inliers to M, / model size
  OutlinePriorResult outline_prior;
  // Points on the page in every photo that frames them, and the fraction of
  // them off M built on the reference outline (-1: no other photos).
  int page_points = 0;
  double page_points_off_mesh = -1;
  // Every end's best fold against the photos' masks (empty: no other photos).
  std::vector<EndFold> end_folds;
  Timings timings;
};

// Throws InputError for inputs that cannot support a mesh (too few points,
// a third of the page without points), naming the part of the page.
Result Run(const Inputs& inputs, const Options& options);

// Logs the warnings, whether the outline prior was used and, with
// options.verbose, every outer iteration of the refinement.
void LogResult(const Result& result, const Options& options);

// init.json (format docunfold.init); `options_record` goes into its producer.
Json ResultToJson(const Inputs& inputs, const Result& result, const Options& options,
                  const Json& options_record, double read_seconds, double write_seconds);
// mesh3d.ply, mesh2d.ply (textured by the reference image) and init.json.
void WriteOutputs(const fs::path& out_dir, const Inputs& inputs, const Result& result,
                  const Options& options, const Json& options_record, double read_seconds);

}  // namespace docunfold::init_mesh
