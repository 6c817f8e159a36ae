#include "stages/optimize/optimize.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "common/axis_direction.h"
#include "common/errors.h"
#include "common/isometry/subdivision.h"
#include "common/program.h"

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

// The segments the rounds cast (the real sides, and unless boundary_only
// the feature segments). Segments whose samples mostly miss the page
// (another detector's file with lines on the table, say) are reported and
// dropped.
std::vector<Segment> PageSegments(const OptimizeInputs& in, const OptimizeOptions& o,
                                  OptimizeResult* result) {
  result->segments = int(in.features.segments.size());
  std::vector<Segment> segments = MakeSegments(in, o, &result->boundary_lines);
  if (segments.empty()) return segments;
  const MarkerSet first = CastMarkers(in.init, in.reference, segments, o.cast);
  std::vector<Segment> kept;
  for (size_t s = 0; s < segments.size(); ++s) {
    const bool on_page = first.markers_of_segment[s] >= 0.5 * double(segments[s].pixels.size());
    if (on_page || segments[s].kind == "boundary") {
      kept.push_back(segments[s]);
    } else {
      ++result->segments_off_page;
    }
  }
  segments.swap(kept);
  if (result->segments_off_page > 0)
    Log("warning: " + std::to_string(result->segments_off_page) + " of " +
        std::to_string(result->segments) +
        " feature segments fall outside the page and are dropped (" + in.features.file.string() +
        ")");
  return segments;
}

// The points projecting into the document region (their indices into
// in.points in result->region_points).
std::vector<Eigen::Vector3d> RegionPoints(const OptimizeInputs& in, const OptimizeOptions& o,
                                          OptimizeResult* result) {
  result->region_points =
      PointsInRegion(in.points, in.reference, ContourRegion(in.boundary, o.region_margin_px));
  if (result->region_points.empty())
    throw InputError(in.boundary.file.string() + ": none of the " +
                     std::to_string(in.points.size()) +
                     " SfM points falls inside the document region");
  std::vector<Eigen::Vector3d> region_points;
  for (const int i : result->region_points) region_points.push_back(in.points[i]);
  return region_points;
}

// init-mesh turned M' upright by the real sides; where the detected
// segments disagree with that by more than a few degrees (a fold taken for
// a side), they turn it, as the lines are kept only near the axes. A turn
// of M' changes no term of F.
void TurnUprightByLines(const OptimizeInputs& in, const OptimizeOptions& o,
                        const std::vector<Segment>& segments, MeshPair* meshes,
                        OptimizeResult* result) {
  const AxisDirection dir = DominantLineDirection(
      *meshes, CastMarkers(*meshes, in.reference, segments, o.cast), segments);
  result->line_direction = dir;
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "segments run %.2f deg off the axes of M' (%d segments, %.0f %% of their "
                "length within 3 deg)",
                dir.angle_deg, dir.lines, 100 * dir.share);
  if (dir.lines >= o.upright_min_segments && dir.share >= o.upright_min_share &&
      std::abs(dir.angle_deg) >= o.upright_min_deg) {
    const Eigen::Rotation2Dd turn(-dir.angle_deg * M_PI / 180);
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (const auto& p : meshes->mesh2d) centre += p;
    centre /= double(meshes->mesh2d.size());
    for (auto& p : meshes->mesh2d) p = centre + turn * (p - centre);
    result->upright_turn_deg = -dir.angle_deg;
    Log(std::string(buf) + ": M' turned by " + Fixed(-dir.angle_deg, 2) + " deg");
  } else {
    Log(std::string(buf) + ": M' left as it is");
  }
}

// The round's lines for lines.json: each solved line with its kind, and the
// pixels and M' points of the markers on it (`kept` maps the solver's
// markers to `current`'s).
std::vector<LineRecord> RoundLines(const isometry::Result& solved, const Grouping& grouping,
                                   const MarkerSet& current, const std::vector<int>& kept,
                                   const MeshPair& meshes) {
  std::vector<LineRecord> lines;
  for (size_t l = 0; l < solved.lines.size() && l < grouping.line_kind.size(); ++l) {
    LineRecord rec;
    rec.kind = grouping.line_kind[l];
    rec.side = grouping.line_side[l];
    rec.segments = grouping.line_segments[l];
    rec.line = solved.lines[l];
    lines.push_back(rec);
  }
  for (size_t k = 0; k < solved.markers.size() && k < kept.size(); ++k) {
    const int line = solved.markers[k].line;
    if (line < 0 || line >= int(lines.size())) continue;
    lines[line].pixels.push_back(current.pixel[kept[k]]);
    lines[line].flat.push_back(PointOnMesh2d(meshes, solved.markers[k].where));
  }
  return lines;
}

// One round of the solver from `round->meshes` (set by the caller) with
// `so`; fills the rest of `round` and returns the solver's point decisions.
std::vector<bool> SolveRound(const OptimizeInputs& in, const OptimizeOptions& o,
                             const std::vector<Segment>& segments,
                             const std::vector<Eigen::Vector3d>& region_points,
                             const std::vector<HullView>& hull_views,
                             const cv::Mat1b& page_interior, const CreaseMap& crease_evidence,
                             isometry::SolveOptions so, RoundResult* round) {
  isometry::Problem problem;
  problem.meshes = round->meshes;
  problem.points = region_points;
  if (!crease_evidence.step.empty())
    problem.fair3d_weights = CreaseFairWeights(round->meshes, in.reference, crease_evidence,
                                               o.crease, &round->crease_triplets);

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
        round->side_markers_dropped =
            DropSideOutliers(*c.meshes, grouping, o.side_outliers, &current, o.side_end_outliers);
      c.markers->clear();
      kept.clear();
      for (size_t i = 0; i < current.markers.size(); ++i)
        if (current.markers[i].line >= 0) {
          c.markers->push_back(current.markers[i]);
          kept.push_back(int(i));
        }
      if (o.mask_hull) {
        const auto hull = HullMarkers(*c.meshes, in.reference, page_interior, hull_views, o.hull);
        c.markers->insert(c.markers->end(), hull.begin(), hull.end());
        round->hull_markers = int(hull.size());
      }
    };
  }
  isometry::Result solved = isometry::Solve(problem, so);
  round->meshes = solved.meshes;
  round->report = solved.report;
  round->lines = RoundLines(solved, grouping, current, kept, round->meshes);
  return solved.point_inlier;
}

void LogHullViews(const std::vector<HullViewCheck>& checks) {
  std::string used, left_out;
  for (const HullViewCheck& c : checks) {
    if (c.used) {
      used += (used.empty() ? "" : ", ") + c.image;
    } else {
      left_out += (left_out.empty() ? "" : ", ") + c.image + " (" +
                  Fixed(100.0 * c.points_outside / std::max(1, c.points_seen), 1) +
                  " % of the points outside it)";
    }
  }
  if (checks.empty()) {
    Log("mask hull: no other photo's page mask (20_boundary/views/)");
  } else {
    Log("mask hull: the page masks of " + (used.empty() ? std::string("no photo") : used) +
        (left_out.empty() ? "" : "; not used: " + left_out));
  }
}

void LogRound(const RoundResult& round) {
  const MeshPair& meshes = round.meshes;
  const isometry::SolveReport& report = round.report;
  const auto& last = report.iterations.back();
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "round %d: %dx%d grid, %zu iterations (%s), F %.4g, %d lines, %d markers "
                "(%d side markers off their side, %d hull), %d creased triplets, %d/%d points "
                "inside, %.1f s",
                round.round, meshes.grid.nx, meshes.grid.ny, report.iterations.size(),
                report.stop_reason.c_str(), last.F, last.lines, last.markers,
                round.side_markers_dropped, round.hull_markers, round.crease_triplets, last.inliers,
                last.inliers + last.outliers, report.seconds);
  Log(buf);
}

// The reader's down in M', through the affine map pixel -> M' over every
// marker of the last round.
std::optional<Eigen::Vector2d> TextDownFlat(const RoundResult& last,
                                            const Eigen::Vector2d& text_down) {
  std::vector<Eigen::Vector2d> pixels, flat;
  for (const LineRecord& l : last.lines)
    for (size_t k = 0; k < l.pixels.size() && k < l.flat.size(); ++k) {
      pixels.push_back(l.pixels[k]);
      flat.push_back(l.flat[k]);
    }
  return CarryDirection(pixels, flat, text_down);
}

}  // namespace

isometry::SolveOptions RoundSolveOptions(const OptimizeOptions& o, int r,
                                         const isometry::Weights& weights) {
  isometry::SolveOptions so = o.solve;
  so.weights = weights;
  const bool first_rounds = r < o.rises_from_round;
  so.converged_iterations = first_rounds ? o.converged_iterations : 1;
  if (first_rounds) so.relative_tolerance = o.first_rounds_tolerance;
  so.max_rises = first_rounds ? 0 : o.max_rises;
  return so;
}

OptimizeResult Run(const OptimizeInputs& in, const OptimizeOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  if (o.rounds < 1) throw UsageError("--rounds must be at least 1");
  OptimizeResult result;
  const std::vector<Segment> segments = PageSegments(in, o, &result);
  const std::vector<Eigen::Vector3d> region_points = RegionPoints(in, o, &result);

  MeshPair meshes = in.init;
  if (o.upright_by_lines && !segments.empty())
    TurnUprightByLines(in, o, segments, &meshes, &result);
  std::vector<HullView> hull_views;
  cv::Mat1b page_interior;
  // The hull holds vertices through E_ray, which is off without segments.
  if (o.mask_hull && !segments.empty()) {
    hull_views = PrepareHullViews(in.other_views);
    page_interior = PageInterior(ContourRegion(in.boundary, 0), o.hull);
    result.hull_views = MarkMaskDoubts(region_points, o.hull, &hull_views);
    LogHullViews(result.hull_views);
  }
  CreaseMap crease_evidence;
  if (o.crease.step > 0 && in.reference_image.empty()) {
    Log("warning: no reference photo (reference.png beside cameras.json): E_fair(M) spares no "
        "crease");
  } else if (o.crease.step > 0) {
    crease_evidence = CreaseEvidence(in.reference_image, ContourRegion(in.boundary, 0), o.crease);
  }
  isometry::Weights weights = o.solve.weights;
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
    round.meshes = meshes;
    result.inliers = SolveRound(in, o, segments, region_points, hull_views, page_interior,
                                crease_evidence, RoundSolveOptions(o, r, weights), &round);
    meshes = round.meshes;
    LogRound(round);
    result.rounds.push_back(std::move(round));
  }
  result.meshes = meshes;
  if (in.features.text_down && !result.rounds.empty())
    result.text_down_flat = TextDownFlat(result.rounds.back(), *in.features.text_down);
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace docunfold::optimize
