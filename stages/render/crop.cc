#include "stages/render/crop.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "common/line_fit.h"
#include "common/statistics.h"

namespace docunfold::render {
namespace {

// Where the viewing ray of `pixel` meets the plane of `triangle`, as a point
// of M' (barycentrics may lie slightly outside the triangle).
std::optional<Eigen::Vector2d> RayThroughTrianglePlane(const MeshPair& mesh,
                                                       const PinholeCamera& camera, int triangle,
                                                       const Eigen::Vector2d& pixel) {
  const Triangle t = mesh.grid.TriangleOf(triangle);
  const Eigen::Vector3d sol =
      RayOnTrianglePlane(camera, {mesh.mesh3d[t[0]], mesh.mesh3d[t[1]], mesh.mesh3d[t[2]]}, pixel);
  if (!sol.allFinite() || sol[2] <= 0) return std::nullopt;
  return (1 - sol[0] - sol[1]) * mesh.mesh2d[t[0]] + sol[0] * mesh.mesh2d[t[1]] +
         sol[1] * mesh.mesh2d[t[2]];
}

// Nearest pixel centre within `radius` that shows M (the lookup at scale 1).
int NearestFace(const PixelToSurface& lookup, const Eigen::Vector2d& p, double radius) {
  const int r = int(std::ceil(radius));
  const int cx = int(std::lround(p.x())), cy = int(std::lround(p.y()));
  int best = -1;
  double best_d2 = radius * radius;
  for (int y = cy - r; y <= cy + r; ++y) {
    for (int x = cx - r; x <= cx + r; ++x) {
      const int f = lookup.FaceAt(x, y);
      if (f < 0) continue;
      const double d2 = (Eigen::Vector2d(x, y) - p).squaredNorm();
      if (d2 <= best_d2) {
        best_d2 = d2;
        best = f;
      }
    }
  }
  return best;
}

}  // namespace

// Evaluations of the lines of the four sides: top/bottom as y(x),
// left/right as x(y).
double YAt(const SideFit& s, double x) {
  return s.point.y() + (x - s.point.x()) * s.direction.y() / s.direction.x();
}
double XAt(const SideFit& s, double y) {
  return s.point.x() + (y - s.point.y()) * s.direction.x() / s.direction.y();
}

std::vector<Eigen::Vector2d> MapPolylineOntoFlat(const MeshPair& mesh, const PinholeCamera& camera,
                                                 const PixelToSurface& lookup,
                                                 const std::vector<Eigen::Vector2d>& polyline,
                                                 double snap_px, int* samples, int max_samples) {
  std::vector<Eigen::Vector2d> out;
  *samples = 0;
  if (polyline.size() < 2) return out;
  double length = 0;
  for (size_t i = 1; i < polyline.size(); ++i) length += (polyline[i] - polyline[i - 1]).norm();
  const double step = std::max(1.0, length / std::max(1, max_samples));
  auto map_one = [&](const Eigen::Vector2d& p) {
    ++*samples;
    if (auto sp = lookup.Lookup(p)) {
      out.push_back(PointOnMesh2d(mesh, *sp));
      return;
    }
    if (snap_px <= 0) return;
    const int f = NearestFace(lookup, p, snap_px);
    if (f < 0) return;
    if (auto q = RayThroughTrianglePlane(mesh, camera, f, p)) out.push_back(*q);
  };
  double carry = 0;  // distance along the polyline to the next sample
  for (size_t i = 1; i < polyline.size(); ++i) {
    const Eigen::Vector2d a = polyline[i - 1], b = polyline[i];
    const double len = (b - a).norm();
    double s = carry;
    for (; s < len; s += step) map_one(a + (b - a) * (s / len));
    carry = s - len;
  }
  map_one(polyline.back());
  return out;
}

SideFit FitSideLine(int side, bool real, const std::vector<Eigen::Vector2d>& flat_points,
                    int samples) {
  SideFit fit;
  fit.real = real;
  fit.samples = samples;
  fit.direction = (side == 0 || side == 2) ? Eigen::Vector2d::UnitX() : Eigen::Vector2d::UnitY();
  if (!real) return fit;
  std::vector<Eigen::Vector2d> pts = flat_points;
  if (pts.size() < 10) {
    fit.mapped = int(pts.size());
    fit.note = "only " + std::to_string(pts.size()) + " of " + std::to_string(samples) +
               " samples map onto the mesh";
    return fit;
  }
  LineFit2d line = FitLineTotalLeastSquares(pts);
  // Drop samples far from the line (a corner rounding, a stray mesh fold),
  // then refit; twice is enough for the few outliers a side has.
  for (int round = 0; round < 2; ++round) {
    const Eigen::Vector2d normal(-line.direction.y(), line.direction.x());
    std::vector<double> res;
    for (const auto& p : pts) res.push_back(std::abs(normal.dot(p - line.point)));
    const double mad = Median(res);
    const double limit = std::max(4.0 * 1.4826 * mad, 1e-12);
    std::vector<Eigen::Vector2d> kept;
    for (size_t i = 0; i < pts.size(); ++i)
      if (res[i] <= limit) kept.push_back(pts[i]);
    if (kept.size() < 10 || kept.size() == pts.size()) break;
    pts = std::move(kept);
    line = FitLineTotalLeastSquares(pts);
  }
  fit.mapped = int(pts.size());
  fit.point = line.point;
  fit.rms = line.rms;
  Eigen::Vector2d d = line.direction;
  const bool horizontal = side == 0 || side == 2;
  // Orient along +x (top, bottom) or +y (left, right).
  if ((horizontal ? d.x() : d.y()) < 0) d = -d;
  fit.direction = d;
  if (fit.mapped < std::max(10.0, 0.3 * samples)) {
    fit.note = "only " + std::to_string(fit.mapped) + " of " + std::to_string(samples) +
               " samples map onto the mesh";
    return fit;
  }
  // A side that runs closer to the other axis means M' is not upright or the
  // boundary's sides are mislabelled; its line would cut the page diagonally.
  if (std::abs(horizontal ? d.x() : d.y()) < std::cos(M_PI / 4)) {
    fit.note = "fitted line is more than 45 degrees off its axis (is M' upright?)";
    return fit;
  }
  fit.used = true;
  return fit;
}

double SlantOf(const SideFit& side, int index) {
  const Eigen::Vector2d d = side.direction;
  // A horizontal direction turned by a is (cos a, sin a); a vertical one
  // is (-sin a, cos a).
  return (index == 0 || index == 2) ? std::atan2(d.y(), d.x()) : std::atan2(-d.x(), d.y());
}

double TiltOfSides(const std::array<SideFit, 4>& sides) {
  double sum = 0, weight = 0;
  for (int i = 0; i < 4; ++i) {
    if (!sides[i].used) continue;
    sum += SlantOf(sides[i], i) * sides[i].mapped;
    weight += sides[i].mapped;
  }
  return weight > 0 ? sum / weight : 0;
}

void RotateSide(SideFit* side, double angle) {
  const Eigen::Rotation2Dd rot(angle);
  side->point = rot * side->point;
  side->direction = rot * side->direction;
}

CropRect ChooseCrop(std::array<SideFit, 4>* sides_in, const Eigen::Vector4d& visible_box) {
  std::array<SideFit, 4>& sides = *sides_in;
  const double cx = 0.5 * (visible_box[0] + visible_box[2]);
  const double cy = 0.5 * (visible_box[1] + visible_box[3]);
  auto drop = [&](int i, const std::string& why) {
    if (!sides[i].used) return;
    sides[i].used = false;
    sides[i].note = why;
  };
  if (sides[0].used && sides[2].used && YAt(sides[0], cx) >= YAt(sides[2], cx)) {
    drop(0, "top line lies below the bottom line in M'");
    drop(2, "bottom line lies above the top line in M'");
  }
  if (sides[3].used && sides[1].used && XAt(sides[3], cy) >= XAt(sides[1], cy)) {
    drop(3, "left line lies right of the right line in M'");
    drop(1, "right line lies left of the left line in M'");
  }
  CropRect crop{visible_box[0], visible_box[1], visible_box[2], visible_box[3], ""};
  // Each line bounds the rectangle where it is tightest over the extent the
  // other sides leave; the lines are within 45 degrees of their axes, so a
  // few alternations settle on the rectangle.
  for (int iter = 0; iter < 8; ++iter) {
    CropRect next = crop;
    if (sides[0].used) next.y0 = std::max(YAt(sides[0], crop.x0), YAt(sides[0], crop.x1));
    if (sides[2].used) next.y1 = std::min(YAt(sides[2], crop.x0), YAt(sides[2], crop.x1));
    if (sides[3].used) next.x0 = std::max(XAt(sides[3], crop.y0), XAt(sides[3], crop.y1));
    if (sides[1].used) next.x1 = std::min(XAt(sides[1], crop.y0), XAt(sides[1], crop.y1));
    crop = next;
  }
  const int used = int(sides[0].used) + sides[1].used + sides[2].used + sides[3].used;
  const double box_w = visible_box[2] - visible_box[0], box_h = visible_box[3] - visible_box[1];
  const bool degenerate = !(crop.Width() > 0.02 * box_w && crop.Height() > 0.02 * box_h) ||
                          !std::isfinite(crop.x0 + crop.x1 + crop.y0 + crop.y1);
  if (used == 0 || degenerate) {
    if (degenerate)
      for (int i = 0; i < 4; ++i) drop(i, "the lines bound no usable rectangle");
    return {visible_box[0], visible_box[1], visible_box[2], visible_box[3], "visible-mesh"};
  }
  crop.rule = used == 4 ? "boundary-lines" : "real-sides-and-visible-mesh";
  return crop;
}

SideWarp WarpToSides(const std::array<SideFit, 4>& sides, const CropRect& crop, double max_slant) {
  SideWarp warp;
  warp.crop = crop;
  warp.lines = sides;
  const double cx = 0.5 * (crop.x0 + crop.x1), cy = 0.5 * (crop.y0 + crop.y1);
  for (int i = 0; i < 4; ++i)
    warp.active[i] = sides[i].used && std::abs(SlantOf(sides[i], i)) <= max_slant;
  if (warp.active[0]) warp.crop.y0 = YAt(sides[0], cx);
  if (warp.active[1]) warp.crop.x1 = XAt(sides[1], cy);
  if (warp.active[2]) warp.crop.y1 = YAt(sides[2], cx);
  if (warp.active[3]) warp.crop.x0 = XAt(sides[3], cy);
  if (!(warp.crop.Width() > 0 && warp.crop.Height() > 0)) {
    warp.active = {};
    warp.crop = crop;
    return warp;
  }
  for (const Eigen::Vector2d& corner :
       {Eigen::Vector2d(warp.crop.x0, warp.crop.y0), Eigen::Vector2d(warp.crop.x1, warp.crop.y0),
        Eigen::Vector2d(warp.crop.x0, warp.crop.y1), Eigen::Vector2d(warp.crop.x1, warp.crop.y1)})
    warp.max_shift = std::max(warp.max_shift, (warp.Apply(corner) - corner).norm());
  return warp;
}

Eigen::Vector2d SideWarp::Apply(const Eigen::Vector2d& p) const {
  const double left = active[3] ? XAt(lines[3], p.y()) : crop.x0;
  const double right = active[1] ? XAt(lines[1], p.y()) : crop.x1;
  const double top = active[0] ? YAt(lines[0], p.x()) : crop.y0;
  const double bottom = active[2] ? YAt(lines[2], p.x()) : crop.y1;
  return {crop.x0 + (p.x() - left) / (right - left) * crop.Width(),
          crop.y0 + (p.y() - top) / (bottom - top) * crop.Height()};
}

PageFormatFit ExtendToPageFormat(CropRect* crop, const std::array<bool, 4>& unseen, double aspect) {
  PageFormatFit fit;
  const bool x_unseen = unseen[1] || unseen[3], y_unseen = unseen[0] || unseen[2];
  if (!x_unseen && !y_unseen) return fit;
  if (x_unseen && y_unseen) {
    fit.note = "sides of both axes are cut off unseen: the page's width is not known";
    return fit;
  }
  fit.axis = x_unseen ? 0 : 1;
  fit.seen = x_unseen ? crop->Width() : crop->Height();
  fit.across = x_unseen ? crop->Height() : crop->Width();
  if (!(aspect >= 1) || !(fit.seen > 0) || !(fit.across > 0)) {
    fit.note = "no usable extent";
    return fit;
  }
  const double shorter = fit.across / aspect, longer = fit.across * aspect;
  if (fit.seen <= shorter) {
    fit.length = shorter;
  } else if (fit.seen <= 1.01 * longer) {
    fit.length = std::max(fit.seen, longer);
  } else {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "the part seen is already %.3f times the page's width, longer than the "
                  "format's %.3f",
                  fit.seen / fit.across, aspect);
    fit.note = buf;
    return fit;
  }
  const double grow = fit.length - fit.seen;
  if (grow <= 0) return fit;
  const int low = x_unseen ? 3 : 0, high = x_unseen ? 1 : 2;
  const double share = unseen[low] && unseen[high] ? 0.5 * grow : grow;
  double& low_edge = x_unseen ? crop->x0 : crop->y0;
  double& high_edge = x_unseen ? crop->x1 : crop->y1;
  if (unseen[low]) low_edge -= share;
  if (unseen[high]) high_edge += share;
  fit.applied = true;
  return fit;
}

}  // namespace docunfold::render
