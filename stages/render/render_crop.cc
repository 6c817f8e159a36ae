// Run's steps from the boundary to the crop: the sides mapped onto M' and
// their lines, the deskew turn, and the crop with the page past cut sides,
// real sides M stops short of, scattered sides and the page format.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common/errors.h"
#include "common/program.h"
#include "common/statistics.h"
#include "stages/render/render_internal.h"

namespace docunfold::render {

namespace {

// The reference's outline scattering about its line in M' along a side is
// how a wrong M shows: on the benchmark sets, every run with a scattered
// side scored at most 0.734 MS-SSIM, most of them for want of a better
// reference photo (docs/decisions/sfm.md, what the choice is worth).
void WarnOfScatteredSides(const RenderInputs& in, double flat_diagonal, RenderResult* r) {
  std::string sides;
  int count = 0;
  double worst_rms = 0;
  for (int i = 0; i < 4; ++i) {
    if (!r->sides[i].scattered) continue;
    sides += std::string(count++ ? " and " : "") + kSideNames[i];
    worst_rms = std::max(worst_rms, r->sides[i].rms / flat_diagonal);
  }
  if (sides.empty()) return;
  std::string warning = "the reference photo's outline does not follow M's edge along its " +
                        sides + (count > 1 ? " sides" : " side") + " in that photo (its samples " +
                        Fixed(100 * worst_rms, 1) +
                        " % of the page's diagonal off their line, rms): M is likely wrong there "
                        "and the page distorted";
  if (!in.other_references.empty())
    warning +=
        "; another photo as the reference may do better (the best other by sfm's "
        "score: REF=" +
        in.other_references.front() + ")";
  r->warnings.push_back(warning);
}

}  // namespace

std::array<std::vector<Eigen::Vector2d>, 4> FitSides(const RenderOptions& options,
                                                     const RenderInputs& in,
                                                     const PixelToSurface& lookup,
                                                     RenderResult* r) {
  const PinholeCamera& cam = in.camera;
  // Boundary sides onto M', their lines, and the tilt they show.
  Eigen::Vector2d flat_lo = in.meshes.mesh2d[0], flat_hi = flat_lo;
  for (const auto& q : in.meshes.mesh2d) {
    flat_lo = flat_lo.cwiseMin(q);
    flat_hi = flat_hi.cwiseMax(q);
  }
  const double flat_diagonal = (flat_hi - flat_lo).norm();
  // A side whose samples scatter about their line is not a straight page
  // edge seen on M (the boundary runs over a fold, or M is far off there).
  auto scatters = [&](const SideFit& fit) { return fit.rms > kMaxSideRms * flat_diagonal; };
  std::array<std::vector<Eigen::Vector2d>, 4> side_points;
  const double snap_px = options.side_snap * std::hypot(cam.width, cam.height);
  for (int i = 0; i < 4; ++i) {
    const BoundarySide& side = in.boundary.sides[i];
    int samples = 0;
    if (side.real)
      side_points[i] = MapPolylineOntoFlat(in.meshes, cam, lookup, side.points, snap_px, &samples);
    r->sides[i] = FitSideLine(i, side.real, side_points[i], samples);
    if (r->sides[i].used && scatters(r->sides[i])) {
      r->sides[i].used = false;
      r->sides[i].scattered = true;
      r->sides[i].note = "samples scatter about their line (rms " +
                         std::to_string(r->sides[i].rms / flat_diagonal) + " of M' diagonal)";
    }
  }
  WarnOfScatteredSides(in, flat_diagonal, r);
  // A side the reference sees edge-on, from the photo that sees it best.
  if (options.edge_on_sides.max_cos > 0) {
    const std::array<SidePlacement, 4> placed =
        PlaceEdgeOnSides(in.meshes, cam, lookup, in.boundary, r->sides, in.views, flat_diagonal,
                         options.edge_on_sides);
    for (int i = 0; i < 4; ++i) {
      r->sides[i].reference_cos = placed[i].reference_cos;
      if (placed[i].view.empty()) continue;
      SideFit fit = FitSideLine(i, true, placed[i].flat, int(placed[i].flat.size()));
      if (!fit.used || scatters(fit)) continue;
      fit.reference_cos = placed[i].reference_cos;
      fit.placed_by = placed[i].view;
      fit.placed_by_cos = placed[i].view_cos;
      Log(std::string(kSideNames[i]) + " side: the reference photo sees it edge-on (|cos| " +
          Fixed(*fit.reference_cos, 2) + "), placed from " + fit.placed_by + " (|cos| " +
          Fixed(fit.placed_by_cos, 2) + ")");
      r->sides[i] = fit;
      side_points[i] = placed[i].flat;
    }
  }
  return side_points;
}

double DeskewAngle(const RenderOptions& options, const RenderInputs& in, RenderResult* r) {
  double angle = 0;
  if (options.deskew) {
    double tilt = TiltOfSides(r->sides);
    std::string source = "sides", what = "boundary lines";
    if (options.deskew_by == DeskewBy::kLines) {
      const AxisDirection mode = DominantAxisDirection(in.lines);
      if (mode.lines >= options.deskew_min_lines && mode.share >= 0.5) {
        tilt = mode.angle_deg * M_PI / 180;
        source = "lines";
        what = "the page's lines";
      }
    }
    if (std::abs(tilt) * 180 / M_PI <= options.max_deskew_deg) {
      angle = -tilt;
      r->deskew_source = source;
    } else {
      Log(what + " are " + Fixed(tilt * 180 / M_PI, 2) +
          " degrees off upright; more than --max-deskew-deg, left as is");
    }
  }
  return angle;
}

namespace {

// The page edge past the sides the reference image cuts off, where the
// other views see it (r->cut_edges): it bounds `visible` there.
void ExtendPastCutSides(const RenderOptions& options, const RenderInputs& in,
                        const std::vector<Eigen::Vector2d>& flat, Eigen::Vector4d* visible_box,
                        RenderResult* r) {
  Eigen::Vector4d& visible = *visible_box;
  std::array<bool, 4> cut;
  for (int i = 0; i < 4; ++i) cut[i] = !in.boundary.sides[i].real;
  r->cut_edges = FindCutSideEdges(in.meshes, flat, visible, cut, in.views, options.cut_sides);
  for (int i = 0; i < 4; ++i) {
    if (!cut[i]) continue;
    const CutSideEdge& e = r->cut_edges[i];
    if (!e.measured) {
      Log(std::string(kSideNames[i]) + " side cut off by the reference image: " + e.note);
      continue;
    }
    // The box stands in for the sides the crop has no line for.
    visible[BoxIndexOfSide(i)] = e.bound;
    const double axis_extent = i % 2 == 0 ? visible[3] - visible[1] : visible[2] - visible[0];
    const std::string share =
        std::to_string(int(std::lround(100 * e.extension / axis_extent))) + " % of the page";
    Log(std::string(kSideNames[i]) + " side cut off by the reference image: " +
        (e.edge_seen ? "the other views see the page edge " + share + " past it (" +
                           std::to_string(e.crossings) + " crossings in " +
                           std::to_string(e.views) + " views)"
                     : "the other views see page up to " + share + " past it, but not its edge (" +
                           std::to_string(e.columns_seen) + " columns)"));
  }
}

// A real side that M stops short of (its border runs inside the outline
// where a blank margin has no points, so too few of the side's samples map
// onto M): the surface is continued past M's border, as for a cut side,
// until it leaves the page in the reference image itself (r->reached_sides;
// it bounds `visible` there). Returns the reference's outline as the view
// the continuation was looked for in (empty when no side was short).
std::vector<ViewMask> ReachRealSides(const RenderOptions& options, const RenderInputs& in,
                                     const std::vector<Eigen::Vector2d>& flat,
                                     Eigen::Vector4d* visible_box, RenderResult* r) {
  const PinholeCamera& cam = in.camera;
  Eigen::Vector4d& visible = *visible_box;
  std::vector<ViewMask> self_view;
  std::array<bool, 4> short_side{};
  for (int i = 0; i < 4; ++i)
    short_side[i] = r->sides[i].real && !r->sides[i].scattered &&
                    (!r->sides[i].used ||
                     r->sides[i].mapped < options.reach_partial_below * r->sides[i].samples);
  if (std::any_of(short_side.begin(), short_side.end(), [](bool s) { return s; })) {
    self_view.push_back({cam,
                         OutlineMask(in.boundary, cam.width, cam.height),
                         in.boundary.file,
                         in.reference_file,
                         {}});
    // The reference's outline first; the other photos' masks may place
    // the side where they see it more squarely.
    std::vector<ViewMask> views = self_view;
    views.insert(views.end(), in.views.begin(), in.views.end());
    CutSideOptions reach = options.cut_sides;
    reach.squarest_view = true;
    const std::array<CutSideEdge, 4> reached =
        FindCutSideEdges(in.meshes, flat, visible, short_side, views, reach);
    for (int i = 0; i < 4; ++i) {
      if (!short_side[i]) continue;
      const CutSideEdge& e = reached[i];
      if (!e.measured || !e.edge_seen || !(e.extension > 0)) continue;
      SideFit& side = r->sides[i];
      if (side.used) {
        // The line where it crosses the middle of the visible box; the
        // reached edge replaces it only if it lies farther out.
        const bool horizontal = i == 0 || i == 2;
        const double mid =
            horizontal ? 0.5 * (visible[0] + visible[2]) : 0.5 * (visible[1] + visible[3]);
        const double line = horizontal ? YAt(side, mid) : XAt(side, mid);
        const bool farther = (i == 0 || i == 3) ? e.bound < line : e.bound > line;
        if (!farther) continue;
        side.used = false;
        side.note = "only " + std::to_string(side.mapped) + " of " + std::to_string(side.samples) +
                    " samples map onto the mesh, and the side lies past their line";
      }
      visible[BoxIndexOfSide(i)] = e.bound;
      r->reached_sides[i] = e;
      const double axis_extent = i % 2 == 0 ? visible[3] - visible[1] : visible[2] - visible[0];
      Log(std::string(kSideNames[i]) + " side lies past M's border: M continued by " +
          Fixed(100 * e.extension / axis_extent, 1) + " % of the page to reach it (" +
          (e.placed_by.empty() ? std::string("where the reference's outline crosses it")
                               : "where " + e.placed_by + "'s page edge crosses it, at |cos| " +
                                     Fixed(e.placed_by_cos, 2)) +
          ")");
    }
  }
  return self_view;
}

// A scattered side bounds `visible` by the median of its samples' coordinate
// across it (M' turned by `rotation`).
void BoundScatteredSides(const std::array<std::vector<Eigen::Vector2d>, 4>& side_points,
                         const Eigen::Rotation2Dd& rotation, Eigen::Vector4d* visible,
                         RenderResult* r) {
  for (int i = 0; i < 4; ++i) {
    if (!r->sides[i].scattered) continue;
    std::vector<double> across;
    for (const auto& p : side_points[i]) {
      const Eigen::Vector2d q = rotation * p;
      across.push_back(i % 2 == 0 ? q.y() : q.x());
    }
    r->sides[i].median_bound = Median(across);
    (*visible)[BoxIndexOfSide(i)] = r->sides[i].median_bound;
  }
}

// The crop lengthened to the page format across cut sides no photo sees
// the edge of (r->page_format).
void ApplyPageFormat(const RenderOptions& options, const RenderInputs& in, CropRect* crop,
                     RenderResult* r) {
  std::array<bool, 4> unseen;
  for (int i = 0; i < 4; ++i)
    unseen[i] =
        !in.boundary.sides[i].real && !(r->cut_edges[i].measured && r->cut_edges[i].edge_seen);
  r->page_format = ExtendToPageFormat(crop, unseen, options.page_aspect);
  const PageFormatFit& f = r->page_format;
  if (f.applied) {
    Log(std::string("no photo sees where the page ends past its cut ") +
        (f.axis == 0 ? "left or right" : "top or bottom") + ": the crop lengthened from " +
        Fixed(f.seen, 3) + " to " + Fixed(f.length, 3) + ", " + Fixed(f.length / f.across, 2) +
        " times its width (--page-format)");
  } else if (!f.note.empty()) {
    Log("page format not applied: " + f.note);
  }
}

}  // namespace

CropStep CropPage(const RenderOptions& options, const RenderInputs& in, const ProjectedMesh& pm,
                  double angle, const std::array<std::vector<Eigen::Vector2d>, 4>& side_points,
                  RenderResult* r) {
  const fs::path m3 = in.meshes_dir / "mesh3d.ply";
  const Eigen::Rotation2Dd rotation(angle);
  CropStep step;
  std::vector<Eigen::Vector2d>& flat = step.flat;
  flat = in.meshes.mesh2d;
  for (auto& q : flat) q = rotation * q;
  for (auto& s : r->sides)
    if (s.used) RotateSide(&s, angle);
  Eigen::Vector4d visible = VisibleBox(pm.raster, pm.triangles, flat);
  if (!(visible[2] > visible[0] && visible[3] > visible[1]))
    throw InputError(m3.string() + ": the mesh covers no pixel of the reference image");
  if (options.extend_cut_sides) ExtendPastCutSides(options, in, flat, &visible, r);
  if (options.reach_real_sides) step.self_view = ReachRealSides(options, in, flat, &visible, r);
  BoundScatteredSides(side_points, rotation, &visible, r);
  step.crop = ChooseCrop(&r->sides, visible);
  if (options.warp_max_slant_deg > 0) {
    const SideWarp warp = WarpToSides(r->sides, step.crop, options.warp_max_slant_deg * M_PI / 180);
    if (std::any_of(warp.active.begin(), warp.active.end(), [](bool a) { return a; })) {
      for (auto& q : flat) q = warp.Apply(q);
      for (auto* edges : {&r->cut_edges, &r->reached_sides})
        for (CutSideEdge& e : *edges)
          for (auto& q : e.strip.flat) q = warp.Apply(q);
      r->warped_sides = warp.active;
      r->warp_max_shift = warp.max_shift;
      r->warp_box = {warp.crop.x0, warp.crop.y0, warp.crop.x1, warp.crop.y1};
      Log("page warped so that the sides' lines are the crop's edges (its corners moved by up to " +
          Fixed(100 * warp.max_shift / std::hypot(warp.crop.Width(), warp.crop.Height()), 2) +
          " % of the diagonal)");
      const std::string rule = step.crop.rule;
      step.crop = warp.crop;
      step.crop.rule = rule;
    }
  }
  for (int i = 0; i < 4; ++i)
    if (r->sides[i].real && !r->sides[i].used && !r->reached_sides[i].measured)
      Log(std::string(kSideNames[i]) + " side not used for the crop: " + r->sides[i].note);
  if (options.page_aspect > 0) ApplyPageFormat(options, in, &step.crop, r);
  r->crop_rule = step.crop.rule;
  return step;
}

}  // namespace docunfold::render
