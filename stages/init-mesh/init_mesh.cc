// init-mesh's Run: the steps of init_mesh.h one after the other.
#include "stages/init-mesh/init_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "common/depth_field.h"
#include "common/errors.h"
#include "common/isometry/mesh_index.h"
#include "common/isometry/metrics.h"
#include "common/isometry/unfold.h"
#include "common/page_files.h"
#include "common/point_index.h"
#include "common/program.h"
#include "common/statistics.h"
#include "stages/init-mesh/init_mesh_internal.h"

namespace docunfold::init_mesh {
namespace {

// The points inside the document region as the reference camera sees them.
struct RegionPoints {
  std::vector<Eigen::Vector3d> points;  // world frame
  std::vector<Eigen::Vector2d> pixels;
  std::vector<double> depths;  // camera depth
  // Those of them that are densify's outline points.
  std::vector<Eigen::Vector2d> outline_pixels;
  std::vector<double> outline_depths;
};

RegionPoints CollectRegionPoints(const Inputs& in, const cv::Mat1b& region) {
  const PinholeCamera& cam = in.reference;
  RegionPoints p;
  for (const int i : PointsInRegion(in.points, cam, region)) {
    const Eigen::Vector3d xc = cam.CamFromWorld(in.points[i]);
    p.points.push_back(in.points[i]);
    p.pixels.push_back(cam.ProjectCam(xc));
    p.depths.push_back(xc.z());
    if (size_t(i) < in.point_sources.size() && in.point_sources[i] == PointSource::kOutline) {
      p.outline_pixels.push_back(p.pixels.back());
      p.outline_depths.push_back(p.depths.back());
    }
  }
  return p;
}

// The world point seen at a pixel of the reference camera at a given depth.
// Not PinholeCamera::LiftAtDepth, whose numbers differ in the last bits:
// Eigen evaluates depth * (K_inv * v) as (depth * K_inv) * v, and R^T * x
// with R^T stored differs from R.transpose() * x; kept as it was so that the
// meshes stay the same to the bit.
class PixelLift {
 public:
  explicit PixelLift(const PinholeCamera& cam)
      : K_inv_(cam.K.inverse()), R_t_(cam.R.transpose()), t_(cam.t) {}
  Eigen::Vector3d At(const Eigen::Vector2d& px, double depth) const {
    const Eigen::Vector3d xc = depth * (K_inv_ * Eigen::Vector3d(px.x(), px.y(), 1));
    return R_t_ * (xc - t_);
  }

 private:
  Eigen::Matrix3d K_inv_, R_t_;
  Eigen::Vector3d t_;
};

// The points that give the grid its depth.
struct DepthPoints {
  std::vector<Eigen::Vector2d> pixels;
  std::vector<double> depths;
  double rbf_scale_px = 0;  // the depth weights' distance unit
};

// Drops the depth outliers (far from the median depth of their image
// neighbours; every point when that leaves fewer than 4) and decides the RBF
// scale (--rbf-scale-px, else the median spacing of the projected points).
DepthPoints DropDepthOutliers(const RegionPoints& region, const Options& o) {
  const std::vector<Eigen::Vector2d>& pixels = region.pixels;
  const std::vector<double>& depths = region.depths;
  DepthPoints kept;
  {
    const PointIndex2d tree(pixels, 10);
    const int k = int(std::min<size_t>(9, pixels.size()));
    std::vector<double> nbr;
    std::vector<double> spacing;
    for (size_t i = 0; i < pixels.size(); ++i) {
      const std::vector<PointIndex2d::Neighbour> nearest = tree.Nearest(pixels[i], k);
      nbr.clear();
      for (const auto& [j, d2] : nearest)
        if (size_t(j) != i) nbr.push_back(depths[size_t(j)]);
      if (nearest.size() > 1) spacing.push_back(std::sqrt(nearest[1].second));
      const double median = Median(nbr);
      if (std::abs(depths[i] - median) <= o.depth_outlier * median) {
        kept.pixels.push_back(pixels[i]);
        kept.depths.push_back(depths[i]);
      }
    }
    kept.rbf_scale_px = o.rbf_scale_px > 0 ? o.rbf_scale_px : std::max(1.0, Median(spacing));
  }
  if (kept.pixels.size() < 4) {  // everything disagrees: use every point
    kept.pixels = pixels;
    kept.depths = depths;
  }
  return kept;
}

// M on the image grid: each vertex lifted by `lift` and, on the Coons grid,
// by the outline prior where it is used (recorded in res->outline_prior).
void LiftGrid(const Inputs& in, const Options& o, const ImageGrid& g, const Lift& lift,
              const RegionPoints& region, const DepthPoints& depth_points, Result* res) {
  const PinholeCamera& cam = in.reference;
  MeshPair& m = res->meshes;
  m.grid = g.grid;
  for (const auto& px : g.pixels) m.mesh3d.push_back(lift(px));
  if (res->grid_source != "coons") {
    res->outline_prior.note = "no boundary sides (grid over the mask's bounding box)";
    return;
  }
  std::vector<double> grid_depths;
  for (const Eigen::Vector3d& x : m.mesh3d) grid_depths.push_back(cam.CamFromWorld(x).z());
  std::array<std::vector<Eigen::Vector2d>, 4> sides;
  std::array<bool, 4> real{};
  for (int s = 0; s < 4; ++s) {
    sides[s] = in.boundary.sides[s].points;
    real[s] = in.boundary.sides[s].real;
  }
  res->outline_prior = OutlinePriorDepths(
      m.grid, g.pixels, grid_depths, sides, real, cam, region.outline_pixels, region.outline_depths,
      depth_points.pixels, depth_points.depths, o.outline_prior);
  if (!res->outline_prior.used) return;
  const PixelLift pixel_lift(cam);
  for (size_t v = 0; v < m.mesh3d.size(); ++v)
    m.mesh3d[v] = pixel_lift.At(g.pixels[v], res->outline_prior.depth[v]);
}

// The joint optimisation without feature lines (λ5 = λ6 = 0) on the points
// of the region; records the inliers and their mean distance to M.
void Refine(const std::vector<Eigen::Vector3d>& points, const Options& o, Result* res) {
  res->inliers = 0;
  isometry::Problem problem;
  problem.meshes = res->meshes;
  problem.points = points;
  isometry::SolveOptions so = o.refine;
  so.weights.line = 0;
  so.weights.ray = 0;
  isometry::Result refined = isometry::Solve(problem, so);
  res->meshes = refined.meshes;
  res->refine = refined.report;
  double distance_sum = 0;
  for (size_t i = 0; i < refined.point_inlier.size(); ++i)
    if (refined.point_inlier[i]) {
      ++res->inliers;
      distance_sum += refined.point_distance[i];
    }
  res->mean_inlier_distance =
      res->inliers ? distance_sum / res->inliers / std::max(refined.report.model_size, 1e-300) : 0;
}

// Unfolds M to the plane (from `initial`, a layout without folds) and
// re-grids the pair on the page.
void Unfold(const std::vector<Eigen::Vector2d>& initial, const Options& o, Result* res) {
  MeshPair& m = res->meshes;
  const auto unfolded = isometry::UnfoldArap(m.grid, m.mesh3d, initial);
  m.mesh2d = unfolded.mesh2d;
  res->unfold_iterations = unfolded.iterations;
  if (o.regrid_on_page) m = RegridOnPage(m);
}

// The fraction of `points` farther than `distance` (fraction of M's model
// size) from M.
double FractionOffMesh(const MeshPair& m, const std::vector<Eigen::Vector3d>& points,
                       double distance) {
  const double limit = distance * isometry::ModelSize(m);
  const isometry::TriangleMeshIndex index(m.mesh3d, m.grid.Triangles());
  int off = 0;
  for (const Eigen::Vector3d& p : points)
    if (!index.Closest(p, limit)) ++off;
  return points.empty() ? 0.0 : double(off) / double(points.size());
}

// The fraction of M's vertices farther than `distance` (fraction of M's
// model size) from every point of `tree`.
double FractionAwayFromPoints(const MeshPair& m, const PointIndex3d& tree, double distance) {
  const double limit = distance * isometry::ModelSize(m);
  int away = 0;
  for (const Eigen::Vector3d& v : m.mesh3d) {
    const auto nearest = tree.Nearest(v, 1);
    if (nearest.empty() || nearest[0].second > limit * limit) ++away;
  }
  return m.mesh3d.empty() ? 0.0 : double(away) / double(m.mesh3d.size());
}

// Mirrors M' when it is a mirror image of the page as the reference photo
// shows it (a flat layout of points is known only up to a reflection):
// quads' signed areas in M' against those of their pictures, by area.
void FaceLikeTheReference(const PinholeCamera& camera, MeshPair* m) {
  double agree = 0;
  for (int q = 0; q < m->grid.NumQuads(); ++q) {
    const std::array<int, 4> c = m->grid.Quad(q);
    auto signed_area = [&](auto at) {
      const Eigen::Vector2d a = at(c[0]), b = at(c[1]), d = at(c[3]);
      const Eigen::Vector2d e1 = b - a, e2 = d - a;
      return e1.x() * e2.y() - e1.y() * e2.x();
    };
    if (camera.CamFromWorld(m->mesh3d[size_t(c[0])]).z() <= 0) continue;
    const double flat = signed_area([&](int v) { return m->mesh2d[size_t(v)]; });
    const double seen = signed_area([&](int v) { return camera.Project(m->mesh3d[size_t(v)]); });
    agree += (flat > 0) == (seen > 0) ? std::abs(seen) : -std::abs(seen);
  }
  if (agree < 0)
    for (Eigen::Vector2d& v : m->mesh2d) v.x() = -v.x();
}

// Where many of the page's points lie off M, the reference outline does not
// bound the page (a panel the reference photo sees edge-on or not at all):
// M is rebuilt from those points and refined on them. It is kept if it
// leaves at most half as many of them off, without reaching farther from
// them (a layout gone wrong covers the points and much else).
void RebuildFromPagePoints(const Inputs& in, const std::vector<ViewPage>& photos, const Options& o,
                           Result* res) {
  const PageFromPointsOptions& po = o.page_from_points;
  const std::vector<bool> on_page = PagePoints(in.points, photos, po);
  std::vector<Eigen::Vector3d> page;
  for (size_t i = 0; i < in.points.size(); ++i)
    if (on_page[i]) page.push_back(in.points[i]);
  res->page_points = int(page.size());
  if (page.empty()) return;
  res->page_points_off_mesh = FractionOffMesh(res->meshes, page, po.off_mesh_distance);
  if (res->page_points_off_mesh <= po.off_mesh_fraction) return;
  const std::string off = Fixed(100 * res->page_points_off_mesh, 1) +
                          " % of the page's points lie off the mesh on the reference outline";
  MeshPair rebuilt;
  std::string why;
  if (!MeshFromPoints(page, o.grid.short_side, o.grid.long_side, po, &rebuilt, &why)) {
    res->warnings.push_back(off + ", but no mesh could be built from them (" + why + ")");
    return;
  }
  FaceLikeTheReference(in.reference, &rebuilt);
  Result from_points = *res;
  from_points.meshes = std::move(rebuilt);
  Unfold(from_points.meshes.mesh2d, o, &from_points);
  Refine(page, o, &from_points);
  const double off_after = FractionOffMesh(from_points.meshes, page, po.off_mesh_distance);
  const PointIndex3d tree(page);
  const double away_before = FractionAwayFromPoints(res->meshes, tree, po.away_distance);
  const double away_after = FractionAwayFromPoints(from_points.meshes, tree, po.away_distance);
  if (!(off_after <= 0.5 * res->page_points_off_mesh) ||
      !(away_after <= away_before + po.away_margin)) {
    res->warnings.push_back(off + "; a mesh built from them leaves " + Fixed(100 * off_after, 1) +
                            " % off and has " + Fixed(100 * away_after, 1) +
                            " % of its vertices (" + Fixed(100 * away_before, 1) +
                            " %) away from them: the first is kept");
    return;
  }
  *res = std::move(from_points);
  res->warnings.push_back(off +
                          " (a part of the page the reference photo does not see): mesh "
                          "built from the points of every photo, " +
                          Fixed(100 * off_after, 1) + " % off it");
  res->grid_source = "page_points";
  res->points_in_region = int(page.size());  // what the refinement had: inliers + outliers
  res->outline_prior = {};
  res->outline_prior.note = "mesh built from the page's points";
}

}  // namespace

Result Run(const Inputs& in, const Options& o) {
  StepTimer timer;
  if (o.grid.short_side < 1 || o.grid.long_side < 1)
    throw UsageError("the grid needs at least 1x1 quads");
  Result res;
  const PinholeCamera& cam = in.reference;
  const std::string image_name = in.reference_image.filename().string();

  // --- The points inside the document region, and the depth they give.
  const cv::Mat1b region = GrowRegion(in.mask, o.mask_margin_px);
  const RegionPoints points = CollectRegionPoints(in, region);
  res.points_total = int(in.points.size());
  res.points_in_region = int(points.points.size());
  if (res.points_in_region < std::max(o.min_points, 4))
    throw InputError(
        "only " + std::to_string(res.points_in_region) + " of " + std::to_string(res.points_total) +
        " SfM points fall inside the document region of " + image_name + " (need at least " +
        std::to_string(std::max(o.min_points, 4)) + " to support the mesh)");
  const DepthPoints depth_points = DropDepthOutliers(points, o);
  res.rbf_scale_px = depth_points.rbf_scale_px;
  res.points_for_depth = int(depth_points.pixels.size());
  const DepthField depth(depth_points.pixels, depth_points.depths, std::max(1, o.depth_neighbours),
                         res.rbf_scale_px, o.depth_model, o.planar_neighbours);
  const PixelLift pixel_lift(cam);
  const Lift lift = [&](const Eigen::Vector2d& px) { return pixel_lift.At(px, depth.At(px)); };
  res.timings.depth = timer.Mark("depth");

  // --- The grid M^r in the image, lifted to M.
  ImageGrid g;
  std::string why;
  if (CoonsGrid(in.boundary, o.grid, lift, region, &g, &why)) {
    res.grid_source = "coons";
  } else {
    res.warnings.push_back("boundary unusable (" + why + "): grid over the mask's bounding box");
    g = BoundingBoxGrid(in.mask, o.grid, lift);
    res.grid_source = "mask_bbox";
  }
  const std::string coverage =
      CheckCoverage(g, points.pixels, cam.width, cam.height, o, image_name);
  if (!coverage.empty()) res.warnings.push_back(coverage);
  LiftGrid(in, o, g, lift, points, depth_points, &res);
  res.timings.grid = timer.Mark("grid");

  // --- Unfold to the plane.
  Unfold(g.pixels, o, &res);
  res.timings.unfold = timer.Mark("unfold");

  Refine(points.points, o, &res);
  res.timings.refine = timer.Mark("refine");

  // Every photo's page, the reference's last: what the page's points and the
  // ends' folds are judged by.
  std::vector<ViewPage> photos = in.other_photos;
  photos.push_back({in.reference, {}, in.mask, {}});
  if (!in.other_photos.empty()) RebuildFromPagePoints(in, photos, o, &res);
  res.timings.page = timer.Mark("page");

  if (!in.other_photos.empty())
    res.end_folds = FoldEnds(photos, in.reference, points.points, o.end_fold, &res.meshes);
  res.timings.ends = timer.Mark("ends");

  if (o.upright) TurnUpright(in, &res);
  res.timings.upright = timer.Mark("upright");

  const auto edge = isometry::IsometryEdgeError(res.meshes);
  res.isometry_error_mean = edge.mean;
  res.isometry_error_max = edge.max;
  res.timings.total = timer.Total();
  return res;
}

}  // namespace docunfold::init_mesh
