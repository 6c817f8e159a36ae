// init-mesh's flags, its inputs and its outputs.
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/option_table.h"
#include "common/page_files.h"
#include "common/ply.h"
#include "common/program.h"
#include "stages/init-mesh/init_mesh.h"

namespace docunfold::init_mesh {
namespace {

// --grid AxB: quads across the page's short side x along its long side.
std::string ParseGrid(const std::string& text, GridQuads* grid) {
  std::smatch match;
  if (!std::regex_match(text, match, std::regex(R"((\d+)x(\d+))")))
    return "expected AxB (quads across the short side x the long side), got '" + text + "'";
  long long a = 0, b = 0;
  try {
    a = std::stoll(match[1]);
    b = std::stoll(match[2]);
  } catch (const std::out_of_range&) {
    a = b = 0;
  }
  if (a < 1 || b < 1 || a > 2000 || b > 2000) return "between 1 and 2000 quads per side";
  grid->short_side = int(a);
  grid->long_side = int(b);
  return "";
}

std::string FormatGrid(const GridQuads& grid) {
  return std::to_string(grid.short_side) + "x" + std::to_string(grid.long_side);
}

}  // namespace

void DeclareOptions(OptionTable& table, Options* o) {
  table.Parsed<GridQuads>("grid", &o->grid, "AxB", ParseGrid, FormatGrid,
                          "quads across the page's short side x along its long side (1 to 2000 "
                          "each)");
  table.Value("k", &o->depth_neighbours, 1, 64, "nearest SfM points per grid vertex for its depth");
  table.Value("rbf-scale-px", &o->rbf_scale_px, 0.0, 1e6,
              "distance unit (px) of the depth weights 1/(1+r^2); 0 = the median spacing of the "
              "projected points, 1 = plain pixels as in the paper");
  table.Choice("depth-model", &o->depth_model,
               {{"planar", DepthModel::kPlanar}, {"average", DepthModel::kAverage}},
               "planar: fit 1/depth as an affine function of the pixel to the nearest --planar-k "
               "points (continues each panel's plane over blank paper); average: the weighted "
               "mean depth of the --k nearest (the paper)");
  table.Value("planar-k", &o->planar_neighbours, 6, 256,
              "nearest SfM points in each planar depth fit");
  table.Value("depth-outlier", &o->depth_outlier, 0.0, 10.0,
              "points off the median depth of their image neighbours by more than this fraction "
              "are not used for the depth");
  table.Value("mask-margin-px", &o->mask_margin_px, 0.0, 1000.0,
              "points this close (px) outside mask.png still count as on the page");
  table.Value("min-points", &o->min_points, 4, 1000000,
              "fewer SfM points on the page is bad input (exit 3)");
  table.Value("min-points-per-ninth", &o->min_points_per_ninth, 1, 1000000,
              "a ninth of the page (3x3 parts of the grid) with fewer SfM points has none");
  table.Value("min-covered-ninths", &o->min_covered_ninths, 0, 9,
              "points in fewer of the page's 9 parts are bad input (exit 3); an empty third is a "
              "warning");
  isometry::DeclareSolveOptions(table, &o->refine);
  table.Switch("upright", &o->upright,
               "turn M' upright by the page's real sides (--no-upright: keep it as unfolded)");
  table.Switch("regrid", &o->regrid_on_page,
               "re-grid uniformly on the page after unfolding (--no-regrid: keep the "
               "image-space grid)");
  table.Switch("outline-prior", &o->outline_prior.enabled,
               "let the page's outline in 3D (densify's outline points) shape blank paper where "
               "the points agree with it (--no-outline-prior: lift the grid by the points alone)");
  table.Value("outline-prior-agreement", &o->outline_prior.agreement, 1e-6, 1.0,
              "the outline's surface counts where the nearby points' depths differ from it by "
              "about this fraction or less (weight exp(-(e/a)^2))");
  table.Value("page-off-mesh", &o->page_from_points.off_mesh_fraction, 0.0, 1.0,
              "rebuild M from the page's points (those on the page in every photo that frames "
              "them) when more than this fraction of them lie off M built on the reference "
              "outline (1: never)");
  table.Switch("end-fold", &o->end_fold.enabled,
               "fold an end of M up on a grid line where the other photos' page masks show it "
               "standing (--no-end-fold: leave the ends as the points and the reference outline "
               "give them)");
  table.Value("end-fold-gain", &o->end_fold.min_gain, 0.0, 1.0,
              "keep a fold when it removes at least this fraction of the mismatch between M's "
              "silhouettes and the photos' page masks");
  table.Switch("verbose", &o->verbose, "log every outer iteration of the refinement");
}

Inputs ReadInputs(const fs::path& sfm_dir, const fs::path& boundary_dir,
                  const fs::path& points_file) {
  Inputs in;
  const fs::path cameras_path = sfm_dir / "cameras.json";
  const CameraSet cameras = ReadCameras(cameras_path);
  if (cameras.reference.empty())
    throw InputError(cameras_path.string() +
                     ": no reference view (expected format docunfold.cameras with \"reference\")");
  in.reference = *cameras.Find(cameras.reference);

  const fs::path points_path = points_file.empty() ? sfm_dir / "points.ply" : points_file;
  PlyData ply = ReadPly(points_path);
  if (ply.vertices.empty()) throw InputError(points_path.string() + ": no points");
  if (const PlyProperty* source = ply.FindProperty("source"))
    for (double v : source->values) in.point_sources.push_back(PointSource(int(v)));
  in.points = std::move(ply.vertices);

  in.reference_image = sfm_dir / "reference.png";
  const cv::Mat image = ReadImage(in.reference_image, cv::IMREAD_REDUCED_GRAYSCALE_2);
  const int w2 = (in.reference.width + 1) / 2, h2 = (in.reference.height + 1) / 2;
  if (std::abs(image.cols - w2) > 1 || std::abs(image.rows - h2) > 1)
    throw InputError(in.reference_image.string() + ": size does not match the reference camera (" +
                     std::to_string(in.reference.width) + "x" +
                     std::to_string(in.reference.height) + " in cameras.json)");

  in.boundary = ReadBoundary(boundary_dir / "boundary.json");

  in.mask = ReadDocumentMask(boundary_dir / "mask.png", in.reference.width, in.reference.height);

  in.other_photos = ReadOtherViewPages(cameras, cameras_path, boundary_dir);
  return in;
}

void LogResult(const Result& result, const Options& o) {
  for (const std::string& w : result.warnings) Log("warning: " + w);
  if (result.outline_prior.used)
    Log("outline prior: " + std::to_string(result.outline_prior.measured_sides) +
        " sides measured, weight " + Fixed(result.outline_prior.mean_weight, 2) + " on average");
  else if (o.outline_prior.enabled)
    Log("outline prior not used: " + result.outline_prior.note);
  if (o.verbose)
    for (const auto& it : result.refine.iterations)
      Log("refine " + std::to_string(it.iteration) + ": F " + std::to_string(it.F) + " (iso " +
          std::to_string(it.terms.iso) + ", dist " + std::to_string(it.terms.dist) + ", fair3d " +
          std::to_string(it.terms.fair3d) + ", fair2d " + std::to_string(it.terms.fair2d) +
          "), inliers " + std::to_string(it.inliers) + ", damping " + std::to_string(it.damping) +
          (it.step_accepted ? "" : ", no step"));
}

Json ResultToJson(const Inputs& in, const Result& r, const Options& o, const Json& options_record,
                  double read_seconds, double write_seconds) {
  Json doc = MakeHeader("docunfold.init", 1, "init-mesh", options_record);
  doc["reference"] = in.reference.image;
  doc["grid"] = {{"nx", r.meshes.grid.nx},
                 {"ny", r.meshes.grid.ny},
                 {"quads", {r.meshes.grid.nx - 1, r.meshes.grid.ny - 1}},
                 {"source", r.grid_source}};
  doc["points"] = {{"total", r.points_total},
                   {"in_region", r.points_in_region},
                   {"used_for_depth", r.points_for_depth},
                   {"inliers", r.inliers},
                   {"outliers", r.points_in_region - r.inliers}};
  doc["depth"] = {{"neighbours", o.depth_neighbours},
                  {"rbf_scale_px", r.rbf_scale_px},
                  {"model", o.depth_model == DepthModel::kPlanar ? "planar" : "average"},
                  {"planar_neighbours", o.planar_neighbours}};
  {
    const OutlinePriorResult& p = r.outline_prior;
    doc["outline_prior"] = {{"used", p.used},
                            {"sides_measured", p.measured_sides},
                            {"outline_points_per_side",
                             {{"top", p.side_points[0]},
                              {"right", p.side_points[1]},
                              {"bottom", p.side_points[2]},
                              {"left", p.side_points[3]}}},
                            {"mean_weight", p.mean_weight}};
    if (!p.note.empty()) doc["outline_prior"]["note"] = p.note;
  }
  doc["page_points"] = {{"photos", in.other_photos.size() + 1}, {"count", r.page_points}};
  if (r.page_points_off_mesh >= 0)
    doc["page_points"]["off_reference_mesh"] = r.page_points_off_mesh;
  static const char* const kEnds[4] = {"first_row", "last_row", "first_column", "last_column"};
  Json folds = Json::array();
  for (const EndFold& f : r.end_folds)
    folds.push_back({{"end", kEnds[f.end]},
                     {"hinge_line", f.hinge_line},
                     {"angle_deg", f.angle_deg},
                     {"length", f.length},
                     {"mask_mismatch_before", f.mismatch_before},
                     {"mask_mismatch_after", f.mismatch_after},
                     {"kept", f.kept}});
  doc["end_folds"] = folds;
  doc["unfold"] = {{"method", "arap"}, {"iterations", r.unfold_iterations}};
  Json refine = isometry::ToJson(r.refine);
  if (!r.refine.iterations.empty()) {
    refine["F_initial"] = r.refine.iterations.front().F;
    refine["F_final"] = r.refine.iterations.back().F;
    refine["terms_final"] = isometry::ToJson(r.refine.iterations.back().terms);
  }
  doc["refine"] = refine;
  doc["quality"] = {{"isometry_edge_error_mean", r.isometry_error_mean},
                    {"isometry_edge_error_max", r.isometry_error_max},
                    {"mean_inlier_distance", r.mean_inlier_distance},
                    {"model_size", r.refine.model_size}};
  doc["upright"] = {{"rotation_deg", r.upright_rotation_deg}, {"from", r.upright_from}};
  doc["warnings"] = r.warnings;
  doc["timings_s"] = {
      {"read", read_seconds},       {"depth", r.timings.depth},
      {"grid", r.timings.grid},     {"unfold", r.timings.unfold},
      {"refine", r.timings.refine}, {"page", r.timings.page},
      {"ends", r.timings.ends},     {"upright", r.timings.upright},
      {"write", write_seconds},     {"total", read_seconds + r.timings.total + write_seconds}};
  return doc;
}

void WriteOutputs(const fs::path& out_dir, const Inputs& in, const Result& r, const Options& o,
                  const Json& options_record, double read_seconds) {
  const auto start = std::chrono::steady_clock::now();
  EnsureDirectory(out_dir);
  MeshPairWriteOptions w;
  w.reference_camera = in.reference;
  w.reference_image = in.reference_image;
  w.comments = {
      std::string("init-mesh ") + ProgramVersion() + ": " + std::to_string(r.meshes.grid.nx - 1) +
          "x" + std::to_string(r.meshes.grid.ny - 1) + " quads (" + r.grid_source + ")",
      "refined: " + std::to_string(r.refine.iterations.size()) +
          " outer iterations, isometry edge error " + Fixed(100 * r.isometry_error_mean, 3) + " %"};
  // init.json last: its presence means the meshes beside it are complete.
  WriteMeshPair(out_dir, r.meshes, w);
  WriteJsonAtomic(out_dir / "init.json",
                  ResultToJson(in, r, o, options_record, read_seconds, SecondsSince(start)));
}

}  // namespace docunfold::init_mesh
