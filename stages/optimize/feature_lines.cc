#include "stages/optimize/feature_lines.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "common/point_index.h"
#include "common/statistics.h"

namespace docunfold::optimize {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Diagonal of M''s bounding box: the unit of the grouping tolerances.
double FlatDiagonal(const MeshPair& meshes) {
  Eigen::Vector2d lo = meshes.mesh2d[0], hi = lo;
  for (const auto& v : meshes.mesh2d) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  return (hi - lo).norm();
}

// A candidate line in M': its points and principal axes.
struct Cluster {
  std::string kind;
  std::vector<int> segments;
  std::vector<Eigen::Vector2d> points;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();
  double t_min = 0, t_max = 0;  // extent along the direction
  double height = 0;            // extent across it
  bool alive = true;

  void Update() {
    centre.setZero();
    for (const auto& p : points) centre += p;
    centre /= double(points.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const auto& p : points) scatter += (p - centre) * (p - centre).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
    direction = eig.eigenvectors().col(1);
    const Eigen::Vector2d normal(-direction.y(), direction.x());
    t_min = 1e300, t_max = -1e300;
    double h_min = 1e300, h_max = -1e300;
    for (const auto& p : points) {
      const double t = (p - centre).dot(direction), h = (p - centre).dot(normal);
      t_min = std::min(t_min, t);
      t_max = std::max(t_max, t);
      h_min = std::min(h_min, h);
      h_max = std::max(h_max, h);
    }
    height = h_max - h_min;
  }
  double Width() const { return t_max - t_min; }
  Eigen::Vector2d End(int k) const { return centre + (k == 0 ? t_min : t_max) * direction; }
};

// Two clusters that may merge into one line; cost: the distance between
// their closest ends.
struct MergeCandidate {
  double cost;
  int a, b;
};

// Pairs of live clusters of one kind, within 10 degrees of parallel, whose
// ends lie in the tolerance box (`gap` along the longer one, `offset`
// across), cheapest first; nullopt when fewer than two clusters are alive.
std::optional<std::vector<MergeCandidate>> MergeCandidates(const std::vector<Cluster>& clusters,
                                                           double gap, double offset) {
  const double cos_parallel = std::cos(10 * kPi / 180);
  std::vector<Eigen::Vector2d> ends;
  std::vector<std::pair<int, int>> owner;  // cluster, end
  for (size_t c = 0; c < clusters.size(); ++c) {
    if (!clusters[c].alive) continue;
    for (int k = 0; k < 2; ++k) {
      ends.push_back(clusters[c].End(k));
      owner.emplace_back(int(c), k);
    }
  }
  if (ends.size() < 4) return std::nullopt;
  const PointIndex2d tree(ends);
  std::vector<MergeCandidate> candidates;
  const double radius2 = gap * gap + offset * offset;
  for (size_t e = 0; e < ends.size(); ++e) {
    const auto [a, ka] = owner[e];
    for (const auto& [f, d2] : tree.WithinSquaredRadius(ends[e], radius2)) {
      const auto [b, kb] = owner[f];
      if (b <= a) continue;
      const Cluster& A = clusters[a];
      const Cluster& B = clusters[b];
      if (A.kind != B.kind) continue;
      if (std::abs(A.direction.dot(B.direction)) < cos_parallel) continue;
      // The tolerance box, aligned with the longer of the two.
      const Eigen::Vector2d u = A.Width() >= B.Width() ? A.direction : B.direction;
      const Eigen::Vector2d d = ends[f] - ends[e];
      const double along = std::abs(d.dot(u)), across = std::abs(d.x() * u.y() - d.y() * u.x());
      if (along > gap || across > offset) continue;
      candidates.push_back({std::sqrt(d2), a, b});
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const MergeCandidate& x, const MergeCandidate& y) { return x.cost < y.cost; });
  return candidates;
}

// Straightness h/w of the union of two clusters, and whether they overlap
// along the line more than a little (then they are two parallel lines, or
// duplicates, not pieces of one).
bool MergedIsStraight(const Cluster& a, const Cluster& b, double max_straightness,
                      double* straightness) {
  Cluster u;
  u.points = a.points;
  u.points.insert(u.points.end(), b.points.begin(), b.points.end());
  u.Update();
  *straightness = u.height / std::max(u.Width(), 1e-12);
  const double overlap = a.Width() + b.Width() - u.Width();
  return *straightness < max_straightness && overlap < 0.3 * std::min(a.Width(), b.Width());
}

}  // namespace

std::vector<Eigen::Vector2d> SamplePolyline(const std::vector<Eigen::Vector2d>& polyline,
                                            double step) {
  std::vector<Eigen::Vector2d> out;
  if (polyline.empty()) return out;
  out.push_back(polyline[0]);
  for (size_t k = 0; k + 1 < polyline.size(); ++k) {
    const Eigen::Vector2d a = polyline[k], b = polyline[k + 1];
    const int n = std::max(1, int(std::ceil((b - a).norm() / std::max(step, 1e-6))));
    for (int j = 1; j <= n; ++j) out.push_back(a + (b - a) * (double(j) / n));
  }
  return out;
}

MarkerSet CastMarkers(const MeshPair& meshes, const PinholeCamera& reference,
                      const std::vector<Segment>& segments, const CastOptions& options) {
  const double pixels = double(reference.width) * reference.height;
  const double scale = std::min(1.0, std::sqrt(options.max_raster_pixels / pixels));
  PixelToSurface map(meshes, reference, scale);
  const Eigen::Vector3d origin = reference.Center();
  MarkerSet set;
  set.markers_of_segment.assign(segments.size(), 0);
  for (size_t s = 0; s < segments.size(); ++s)
    for (size_t k = 0; k < segments[s].pixels.size(); ++k) {
      const Eigen::Vector2d& px = segments[s].pixels[k];
      const auto where = map.LookupNear(px, options.snap_px);
      if (!where) continue;
      isometry::Marker m;
      m.where = *where;
      m.ray_origin = origin;
      m.ray_direction = reference.RayDirection(px);
      m.line = -1;
      set.markers.push_back(m);
      set.segment.push_back(int(s));
      set.pixel.push_back(px);
      ++set.markers_of_segment[s];
    }
  return set;
}

Grouping GroupSegments(const MeshPair& meshes, const MarkerSet& markers,
                       const std::vector<Segment>& segments, const GroupingOptions& o) {
  const double diag = FlatDiagonal(meshes);
  const double gap = o.gap * diag, offset = o.offset * diag;

  std::vector<std::vector<Eigen::Vector2d>> points(segments.size());
  for (size_t i = 0; i < markers.markers.size(); ++i)
    points[markers.segment[i]].push_back(PointOnMesh2d(meshes, markers.markers[i].where));

  Grouping g;
  g.line_of_segment.assign(segments.size(), -1);
  std::vector<Cluster> clusters;
  for (size_t s = 0; s < segments.size(); ++s) {
    if (int(points[s].size()) < o.min_markers) continue;
    if (segments[s].kind == "boundary") {
      g.line_of_segment[s] = int(g.line_kind.size());
      g.line_kind.push_back("boundary");
      g.line_side.push_back(segments[s].side);
      g.line_segments.push_back(1);
      continue;
    }
    Cluster c;
    c.kind = segments[s].kind;
    c.segments = {int(s)};
    c.points = points[s];
    c.Update();
    // A segment already bent in M' (across a crease, say) is no evidence of
    // a straight line.
    if (c.height / std::max(c.Width(), 1e-12) >= o.straightness) continue;
    clusters.push_back(std::move(c));
  }

  for (bool merged = true; merged;) {
    merged = false;
    const std::optional<std::vector<MergeCandidate>> candidates =
        MergeCandidates(clusters, gap, offset);
    if (!candidates) break;
    std::vector<char> touched(clusters.size(), 0);
    for (const MergeCandidate& c : *candidates) {
      if (touched[c.a] || touched[c.b] || !clusters[c.a].alive || !clusters[c.b].alive) continue;
      double straightness = 0;
      if (!MergedIsStraight(clusters[c.a], clusters[c.b], o.straightness, &straightness)) continue;
      Cluster& A = clusters[c.a];
      Cluster& B = clusters[c.b];
      A.points.insert(A.points.end(), B.points.begin(), B.points.end());
      A.segments.insert(A.segments.end(), B.segments.begin(), B.segments.end());
      A.Update();
      B.alive = false;
      touched[c.a] = touched[c.b] = 1;
      merged = true;
      ++g.merges;
    }
  }

  // In the upright M' the page's lines run along the axes.
  const double axis = std::sin(o.axis_tolerance_deg * kPi / 180);
  for (const Cluster& c : clusters) {
    if (!c.alive) continue;
    if (std::min(std::abs(c.direction.x()), std::abs(c.direction.y())) > axis) continue;
    const int line = int(g.line_kind.size());
    for (int s : c.segments) g.line_of_segment[s] = line;
    g.line_kind.push_back(c.kind);
    g.line_side.push_back(-1);
    g.line_segments.push_back(int(c.segments.size()));
  }
  return g;
}

AxisDirection DominantLineDirection(const MeshPair& meshes, const MarkerSet& markers,
                                    const std::vector<Segment>& segments) {
  std::vector<std::vector<Eigen::Vector2d>> flat(segments.size());
  for (size_t i = 0; i < markers.markers.size(); ++i)
    flat[markers.segment[i]].push_back(PointOnMesh2d(meshes, markers.markers[i].where));
  std::vector<DirectionVote> votes;
  for (size_t s = 0; s < segments.size(); ++s) {
    if (segments[s].kind == "boundary" || flat[s].size() < 3) continue;
    Cluster c;
    c.points = flat[s];
    c.Update();
    if (c.Width() <= 0 || c.height > 0.1 * c.Width()) continue;  // not straight in M'
    votes.push_back({std::atan2(c.direction.y(), c.direction.x()) * 180 / kPi, c.Width()});
  }
  return DominantAxisDirection(votes);
}

std::vector<isometry::FeatureLine> AssignLines(const MeshPair& meshes, const Grouping& grouping,
                                               MarkerSet* markers, AxisLines axis_lines) {
  const int n = int(grouping.line_kind.size());
  std::vector<Eigen::Vector2d> sum(n, Eigen::Vector2d::Zero());
  std::vector<Eigen::Matrix2d> outer(n, Eigen::Matrix2d::Zero());
  std::vector<int> count(n, 0);
  for (size_t i = 0; i < markers->markers.size(); ++i) {
    const int line = grouping.line_of_segment[markers->segment[i]];
    markers->markers[i].line = line;
    if (line < 0) continue;
    const Eigen::Vector2d p = PointOnMesh2d(meshes, markers->markers[i].where);
    sum[line] += p;
    outer[line] += p * p.transpose();
    ++count[line];
  }
  std::vector<isometry::FeatureLine> lines(n);
  for (int l = 0; l < n; ++l) {
    if (count[l] < 2) continue;
    const Eigen::Vector2d mean = sum[l] / count[l];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(outer[l] / count[l] -
                                                       mean * mean.transpose());
    const Eigen::Vector2d normal = eig.eigenvectors().col(0);
    lines[l].theta = std::atan2(normal.y(), normal.x());
    lines[l].offset = normal.dot(mean);
  }
  for (int l = 0; l < n; ++l) {
    lines[l].axis_aligned = axis_lines == AxisLines::kAll || (axis_lines == AxisLines::kFeatures &&
                                                              grouping.line_kind[l] != "boundary");
  }
  return lines;
}

int DropSideOutliers(const MeshPair& meshes, const Grouping& grouping, double tolerance,
                     MarkerSet* markers, double end_factor) {
  const int n = int(grouping.line_kind.size());
  const double diagonal = FlatDiagonal(meshes);
  std::vector<std::vector<int>> of_line(n);
  for (size_t i = 0; i < markers->markers.size(); ++i) {
    const int l = markers->markers[i].line;
    if (l >= 0 && grouping.line_kind[l] == "boundary") of_line[l].push_back(int(i));
  }
  int dropped = 0;
  for (int l = 0; l < n; ++l) {
    std::vector<int> kept = of_line[l];
    // Twice: the first fit is pulled toward the outliers.
    for (int pass = 0; pass < 2 && kept.size() >= 3; ++pass) {
      Cluster c;
      for (const int i : kept) c.points.push_back(PointOnMesh2d(meshes, markers->markers[i].where));
      c.Update();
      const Eigen::Vector2d normal(-c.direction.y(), c.direction.x());
      // Beyond the tolerance and beyond the side's own scatter about its
      // fitted line (4 sigma, robustly estimated): a side that scatters
      // evenly keeps its markers, and so does a long run off the line, which
      // the fit leans toward (a notch is short; a whole flap is not this
      // function's to judge).
      std::vector<double> residual;
      for (const auto& p : c.points) residual.push_back(std::abs((p - c.centre).dot(normal)));
      const double limit = std::max(tolerance * diagonal, 4 * 1.4826 * Median(residual));
      // Only inside the side: toward its corners M is least certain, and
      // there the line is what holds the page's edge straight.
      const double end = 0.1 * c.Width();
      std::vector<int> next;
      for (size_t k = 0; k < kept.size(); ++k) {
        const double t = (c.points[k] - c.centre).dot(c.direction);
        const bool at_end = t < c.t_min + end || t > c.t_max - end;
        if (residual[k] <= limit ||
            (at_end && (end_factor <= 0 || residual[k] <= end_factor * limit)))
          next.push_back(kept[k]);
      }
      if (next.size() < 3) break;
      kept = std::move(next);
    }
    if (kept.size() == of_line[l].size()) continue;
    std::vector<char> keep(markers->markers.size(), 0);
    for (const int i : kept) keep[size_t(i)] = 1;
    for (const int i : of_line[l])
      if (!keep[size_t(i)]) {
        markers->markers[i].line = -1;
        ++dropped;
      }
  }
  return dropped;
}

}  // namespace docunfold::optimize
