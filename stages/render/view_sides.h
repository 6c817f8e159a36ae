// A page side the reference photo sees edge-on, placed from the photo that
// sees it best. Where the reference's rays graze M along a side, an error
// of d in M's depth there moves the point they meet by about d / tan(angle)
// along the page, and the crop with it (set02's last panel, which its
// reference photo sees 6-10° off the surface: an M nearer the truth moved
// its bottom side by 0.3 % of the diagonal). Another photo's page outline,
// cast onto M through that photo's own rays where they meet M squarely,
// lands much nearer the page's edge.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"
#include "common/page_files.h"
#include "stages/render/cut_sides.h"

namespace docunfold::render {

struct SideFit;  // render.h, which holds these options

struct EdgeOnSideOptions {
  // A real side is edge-on when the median |cos| of the angle between the
  // reference's rays along it and M's normal where they meet M is below
  // this (0.5: the rays within 30° of the surface, where a depth error of M
  // moves the side along the page by 1.7 times as much). 0: every side from
  // the reference photo.
  double max_cos = 0.5;
  // A depth error d of M moves the point a ray meets along the page by d
  // times tan of the angle between ray and normal (at the median |cos|).
  // Another photo places the side when its tan is below the reference's by
  // at least this much, from at least `min_samples` outline pixels: it must
  // save more than its misregistration with M costs, about one d.
  double min_tan_saving = 1.0;
  int min_samples = 60;
  // An outline sample belongs to the side whose line in M' lies within this
  // fraction of M's diagonal and every other side's line at least twice as
  // far (samples near corners belong to neither).
  double near_side = 0.02;
  // Outline pixels this close to the photo's border are where the photo
  // cuts the page, not its edge (fraction of the photo's diagonal).
  double frame_margin = 0.01;
};

// A sample of a photo's page outline cast onto M.
struct OutlineOnMesh {
  Eigen::Vector2d flat;  // where it lands in M'
  double cos = 0;        // cos between its ray and M's normal (by the triangles' winding)
};

// The outer contour of `view`'s page mask (photo pixels away from the
// photo's border), undistorted and cast onto M through the view's rays;
// samples whose ray misses M are left out.
std::vector<OutlineOnMesh> CastOutlineOntoMesh(const MeshPair& mesh, const ViewMask& view,
                                               double frame_margin);

// The median |cos| between `camera`'s rays through `pixels` and M's normal
// where they meet M (`lookup`: M rasterised in `camera`); nullopt when none
// does (the side lies past M's border).
std::optional<double> MedianRayCos(const MeshPair& mesh, const PinholeCamera& camera,
                                   const PixelToSurface& lookup,
                                   const std::vector<Eigen::Vector2d>& pixels);

// What placed one side.
struct SidePlacement {
  std::optional<double> reference_cos;  // median |cos| along the side, reference photo
  std::string view;                     // the photo that placed it; empty: the reference
  double view_cos = 0;                  // its median |cos| there
  std::vector<Eigen::Vector2d> flat;    // its outline samples on the side, in M'
};

// For every used side of `sides` (fitted from the reference's boundary,
// whose pixels are `boundary`) that the reference sees edge-on: the other
// photo in `views` that sees M most squarely along it, and from the side
// the reference sees, with its outline samples there (`flat_diagonal`: M's
// diagonal in M', the unit of options.near_side). Sides not edge-on, or no
// photo much better, keep an empty view.
std::array<SidePlacement, 4> PlaceEdgeOnSides(
    const MeshPair& mesh, const PinholeCamera& reference, const PixelToSurface& lookup,
    const Boundary& boundary, const std::array<SideFit, 4>& sides,
    const std::vector<ViewMask>& views, double flat_diagonal, const EdgeOnSideOptions& options);

}  // namespace docunfold::render
