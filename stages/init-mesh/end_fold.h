// An end of the page folded up steeply where the points are too few to show
// it (a receipt's total standing up at a crease): the reference photo sees
// such an end at a grazing angle, and M, smooth over it, continues the panel
// before it to the reference outline, a shorter page than the paper. The
// other photos' page masks see the end standing: each end of M is tried as a
// plane hinged on a grid line and turned through an angle, its length set
// so that its far edge stays on the reference outline, and the hinge and
// angle whose silhouettes agree best with every photo's mask are kept when
// they agree clearly better than M as it was.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"
#include "common/page_files.h"

namespace docunfold::init_mesh {

struct EndFoldOptions {
  bool enabled = true;
  // Hinges are tried on the grid lines up to this fraction of the grid's
  // lines from each end.
  double max_flap_fraction = 0.35;
  // Fold angles tried, either way from the panel before the hinge (degrees),
  // first every `coarse_step_deg`, then every degree around the best.
  double max_angle_deg = 150;
  double coarse_step_deg = 5;
  // A flap is at most this many times as long as the part of M it replaces.
  double max_length_ratio = 3;
  // The silhouettes are compared on masks this many pixels wide.
  int raster_width = 320;
  // A fold is kept when it removes at least `min_gain` of the mismatch
  // between M's silhouettes and the masks (pixels in one but not the other,
  // summed over the photos), and at least `min_gain_area` of the masks'
  // total area.
  double min_gain = 0.25;
  double min_gain_area = 0.01;
  // An end with a vertex this close to the reference image's border (pixels)
  // is cut off by the photo, not the page's side: it is not folded.
  double border_margin_px = 3;
  // The points are what M follows; a fold may take at most this fraction of
  // them (net) farther than `point_distance` (fraction of M's model size)
  // from M: an end the points hold is not folded.
  double max_points_lost = 0.01;
  double point_distance = 0.02;
};

// One end's best fold. `end`: 0 first row, 1 last row, 2 first column, 3
// last column of the grid; `hinge_line`: grid lines from that end to the
// hinge; `angle_deg`: the turn about the hinge from the panel before it;
// `length`: the flap's length, in M's units; mismatches as fractions of the
// masks' total area.
struct EndFold {
  int end = -1;
  int hinge_line = 0;
  double angle_deg = 0;
  double length = 0;
  double mismatch_before = 0;
  double mismatch_after = 0;
  // Points within reach of M before the fold and not after, net of those
  // the other way (fraction of the points).
  double points_lost = 0;
  bool kept = false;
};

// The masks' views: the reference (its mask, no distortion) and the other
// photos; `points`: the page's points M was fitted to. Returns the best fold
// of every end the reference photo does not cut off; folds the kept ones
// into `m` (M and M' alike, M' flat and as long as the flap).
std::vector<EndFold> FoldEnds(const std::vector<ViewPage>& photos, const PinholeCamera& reference,
                              const std::vector<Eigen::Vector3d>& points, const EndFoldOptions& o,
                              MeshPair* m);

}  // namespace docunfold::init_mesh
