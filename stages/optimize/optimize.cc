#include "stages/optimize/optimize.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "common/axis_direction.h"
#include "common/cli.h"
#include "common/errors.h"
#include "common/isometry/subdivision.h"

namespace docunfold::optimize {
namespace {

std::vector<Segment> MakeSegments(const OptimizeInputs& in, const OptimizeOptions& o,
                                  int* boundary_lines) {
  std::vector<Segment> segments;
  *boundary_lines = 0;
  if (!o.features) return segments;
  for (int i = 0; i < 4; ++i) {
    if (!in.boundary.sides[i].real) continue;
    segments.push_back(
        {"boundary", i, SamplePolyline(in.boundary.sides[i].points, o.marker_step_px)});
    ++*boundary_lines;
  }
  if (o.boundary_only) return segments;
  for (const FeatureSegment& f : in.features.segments)
    segments.push_back({f.kind, -1, SamplePolyline(f.points, o.marker_step_px)});
  return segments;
}

}  // namespace

OptimizeResult Run(const OptimizeInputs& in, const OptimizeOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  if (o.rounds < 1) throw UsageError("--rounds must be at least 1");
  OptimizeResult result;
  result.segments = int(in.features.segments.size());
  std::vector<Segment> segments = MakeSegments(in, o, &result.boundary_lines);

  // Segments whose samples mostly miss the page (another detector's file
  // with lines on the table, say) are reported and dropped.
  if (!segments.empty()) {
    const MarkerSet first = CastMarkers(in.init, in.reference, segments, o.cast);
    std::vector<Segment> kept;
    for (size_t s = 0; s < segments.size(); ++s) {
      const bool on_page = first.markers_of_segment[s] >= 0.5 * double(segments[s].pixels.size());
      if (on_page || segments[s].kind == "boundary") {
        kept.push_back(segments[s]);
      } else {
        ++result.segments_off_page;
      }
    }
    segments.swap(kept);
    if (result.segments_off_page > 0)
      Log("warning: " + std::to_string(result.segments_off_page) + " of " +
          std::to_string(result.segments) +
          " feature segments fall outside the page and are dropped (" + in.features.file.string() +
          ")");
  }

  result.region_points =
      PointsInRegion(in.points, in.reference, ContourRegion(in.boundary, o.region_margin_px));
  if (result.region_points.empty())
    throw InputError(in.boundary.file.string() + ": none of the " +
                     std::to_string(in.points.size()) +
                     " SfM points falls inside the document region");
  std::vector<Eigen::Vector3d> region_points;
  for (const int i : result.region_points) region_points.push_back(in.points[i]);

  MeshPair meshes = in.init;
  // init-mesh turned M' upright by the real sides; where the detected
  // segments disagree with that by more than a few degrees (a fold taken for
  // a side), they turn it, as the lines are kept only near the axes. A turn
  // of M' changes no term of F.
  if (o.upright_by_lines && !segments.empty()) {
    const AxisDirection dir = DominantLineDirection(
        meshes, CastMarkers(meshes, in.reference, segments, o.cast), segments);
    result.line_direction = dir;
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "segments run %.2f deg off the axes of M' (%d segments, %.0f %% of their "
                  "length within 3 deg)",
                  dir.angle_deg, dir.lines, 100 * dir.share);
    if (dir.lines >= o.upright_min_segments && dir.share >= o.upright_min_share &&
        std::abs(dir.angle_deg) >= o.upright_min_deg) {
      const Eigen::Rotation2Dd turn(-dir.angle_deg * M_PI / 180);
      Eigen::Vector2d centre = Eigen::Vector2d::Zero();
      for (const auto& p : meshes.mesh2d) centre += p;
      centre /= double(meshes.mesh2d.size());
      for (auto& p : meshes.mesh2d) p = centre + turn * (p - centre);
      result.upright_turn_deg = -dir.angle_deg;
      Log(std::string(buf) + ": M' turned by " + std::to_string(-dir.angle_deg).substr(0, 6) +
          " deg");
    } else {
      Log(std::string(buf) + ": M' left as it is");
    }
  }
  isometry::Weights weights = o.weights;
  if (segments.empty()) weights.line = weights.ray = 0;
  for (int r = 0; r < o.rounds; ++r) {
    if (r > 0) {
      meshes = isometry::SubdivideCatmullClark(meshes);
      weights.line *= o.feature_weight_growth;
      weights.ray *= o.feature_weight_growth;
    }
    RoundResult round;
    round.round = r;
    round.weights = weights;
    round.start_seconds = SecondsSince(start);

    isometry::Problem problem;
    problem.meshes = meshes;
    problem.points = region_points;
    isometry::SolveOptions so;
    so.weights = weights;
    so.outlier_distance = o.outlier_distance;
    so.iso_edges = o.iso_edges;
    so.relative_tolerance = o.relative_tolerance;
    so.converged_iterations = r < o.rises_from_round ? o.converged_iterations : 1;
    so.max_outer_iterations = o.max_outer_iterations;
    so.max_rises = r >= o.rises_from_round ? o.max_rises : 0;
    so.method = o.method;
    so.linear_solver = o.linear_solver;
    so.project_markers = o.project;
    so.num_threads = o.threads;

    // Every outer iteration: the samples' rays meet the current M, their
    // points in M' are grouped into lines, and only markers on a line stay.
    MarkerSet current;
    Grouping grouping;
    std::vector<int> kept;  // solver marker -> index in `current`
    if (!segments.empty()) {
      so.on_outer_iteration = [&](const isometry::OuterIterationContext& c) {
        current = CastMarkers(*c.meshes, in.reference, segments, o.cast);
        grouping = GroupSegments(*c.meshes, current, segments, o.grouping);
        *c.lines = AssignLines(*c.meshes, grouping, &current, o.axis_lines);
        if (o.side_outliers > 0)
          round.side_markers_dropped =
              DropSideOutliers(*c.meshes, grouping, o.side_outliers, &current, o.side_end_outliers);
        c.markers->clear();
        kept.clear();
        for (size_t i = 0; i < current.markers.size(); ++i)
          if (current.markers[i].line >= 0) {
            c.markers->push_back(current.markers[i]);
            kept.push_back(int(i));
          }
      };
    }
    isometry::Result solved = isometry::Solve(problem, so);
    meshes = solved.meshes;
    round.meshes = meshes;
    round.report = solved.report;
    for (size_t l = 0; l < solved.lines.size() && l < grouping.line_kind.size(); ++l) {
      LineRecord rec;
      rec.kind = grouping.line_kind[l];
      rec.side = grouping.line_side[l];
      rec.segments = grouping.line_segments[l];
      rec.line = solved.lines[l];
      round.lines.push_back(rec);
    }
    for (size_t k = 0; k < solved.markers.size() && k < kept.size(); ++k) {
      const int line = solved.markers[k].line;
      if (line < 0 || line >= int(round.lines.size())) continue;
      round.lines[line].pixels.push_back(current.pixel[kept[k]]);
      round.lines[line].flat.push_back(PointOnMesh2d(meshes, solved.markers[k].where));
    }
    result.inliers = solved.point_inlier;
    const auto& last = solved.report.iterations.back();
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "round %d: %dx%d grid, %zu iterations (%s), F %.4g, %d lines, %d markers "
                  "(%d side markers off their side), %d/%d points inside, %.1f s",
                  r, meshes.grid.nx, meshes.grid.ny, solved.report.iterations.size(),
                  solved.report.stop_reason.c_str(), last.F, last.lines, last.markers,
                  round.side_markers_dropped, last.inliers, last.inliers + last.outliers,
                  solved.report.seconds);
    Log(buf);
    result.rounds.push_back(std::move(round));
  }
  result.meshes = meshes;
  if (in.features.text_down && !result.rounds.empty()) {
    // Through the affine map pixel -> M' over every marker of the last round.
    std::vector<Eigen::Vector2d> pixels, flat;
    for (const LineRecord& l : result.rounds.back().lines)
      for (size_t k = 0; k < l.pixels.size() && k < l.flat.size(); ++k) {
        pixels.push_back(l.pixels[k]);
        flat.push_back(l.flat[k]);
      }
    result.text_down_flat = CarryDirection(pixels, flat, *in.features.text_down);
  }
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace docunfold::optimize
