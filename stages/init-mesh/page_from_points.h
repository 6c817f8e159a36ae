// M built from the page's points alone, for a page the reference outline
// does not bound (a panel the reference photo sees edge-on or not at all, a
// part outside its frame):
//  1. the page's points: those inside the page mask of every photo that
//     frames them (a point of the table lies outside the page in some photo);
//  2. their flat layout by Isomap: the points thinned to one per cell of a
//     grid in space (print gives dense clusters, blank paper none), each
//     moved onto the plane of its nearest points (the noise across the page
//     would lengthen every path along it), geodesic
//     distances along a graph joining each point to its nearest point in
//     each direction around it (not its k nearest, nor all within a radius:
//     outline points and columns of print would give chains that meet the
//     rest at one place, or not at all, across blank paper), laid out in the plane by
//     landmark MDS (de Silva and Tenenbaum, 2004) — an isometric unfolding
//     of a developable page;
//  3. the page's rectangle around that layout, its orientation that of the
//     smallest-area rectangle;
//  4. a grid over the rectangle, each vertex placed in 3D by a weighted
//     affine fit to its nearest points in the layout.
// Surfaces that nearly touch themselves (a flap folded flat onto the page)
// defeat step 2: neighbours then join the two layers.
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"
#include "common/page_files.h"

namespace docunfold::init_mesh {

struct PageFromPointsOptions {
  // M is rebuilt from the points when more than `off_mesh_fraction` of the
  // page's points lie farther than `off_mesh_distance` (fraction of M's model
  // size) from M built on the reference outline; 1 never rebuilds.
  double off_mesh_fraction = 0.01;
  double off_mesh_distance = 0.02;
  // The rebuilt M is kept only if no more than `away_margin` more of its
  // vertices than of the first M's lie farther than `away_distance` (fraction
  // of the model size) from every point of the page.
  double away_distance = 0.05;
  double away_margin = 0.05;
  // A point up to this many pixels outside a photo's page mask is inside.
  double mask_margin_px = 6;
  // A point is the page's only when at least this many photos frame it.
  int min_photos = 2;
  // Cells of the thinning grid across the points' extent (between their 1st
  // and 99th percentiles, per axis).
  double cells_across = 80;
  int plane_neighbours = 30;  // points in each local plane fit
  // The graph joins each point to its nearest point in each of
  // `graph_sectors` directions, up to `graph_reach_cells` away (across a
  // page's blank margin).
  int graph_sectors = 8;
  double graph_reach_cells = 25;
  int landmarks = 200;      // landmark points of the MDS layout
  int fit_neighbours = 16;  // points in each grid vertex's affine fit
  // Share of the points (per side) left outside the page's rectangle:
  // strays of the layout do not stretch it.
  double rectangle_trim = 0.003;
};

// Which of `points` are the page's: framed by at least o.min_photos of
// `photos` and inside the page (within o.mask_margin_px) in every one that
// frames them.
std::vector<bool> PagePoints(const std::vector<Eigen::Vector3d>& points,
                             const std::vector<ViewPage>& photos, const PageFromPointsOptions& o);

// The points' flat layout (step 2): flat[i] is the position of
// points[used[i]], in the points' length unit; `used` holds the thinned
// points of the largest connected part of the neighbour graph.
struct FlatLayout {
  std::vector<int> used;
  std::vector<Eigen::Vector3d> position;  // of each, moved onto its local plane
  std::vector<Eigen::Vector2d> flat;
};

// False (and why) when there are too few points or they lie on a line.
bool LayOutFlat(const std::vector<Eigen::Vector3d>& points, const PageFromPointsOptions& o,
                FlatLayout* out, std::string* why);

// Steps 2-4: M with `quads_short` x `quads_long` quads (across and along the
// rectangle's longer side), M' its layout in the plane (to be unfolded
// again: Isomap's graph distances run a little long). False (and why) when
// the layout fails.
bool MeshFromPoints(const std::vector<Eigen::Vector3d>& points, int quads_short, int quads_long,
                    const PageFromPointsOptions& o, MeshPair* out, std::string* why);

}  // namespace docunfold::init_mesh
