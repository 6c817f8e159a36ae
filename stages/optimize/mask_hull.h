// The other photos' page masks as a visual hull: every point of the page
// projects inside every photo's page (where the photo shows it at all), so
// a page vertex of M that projects outside one is held to the plane through
// that camera and the mask's outline nearest its projection.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"
#include "common/isometry/isometry.h"
#include "common/page_files.h"

namespace docunfold::optimize {

struct HullOptions {
  // A vertex farther than this outside a mask (pixels of that photo) gets a
  // marker.
  double outside_px = 4;
  // Only vertices this far inside the reference page (reference pixels) are
  // page vertices: M runs on past the page on purpose.
  double page_inset_px = 12;
  // Projections this close to a photo's border are not judged there (the
  // page may run out of the photo).
  double image_border_px = 5;
  // A hull marker's weight in E_ray (a text sample's is 1): there are tens
  // of them against thousands of samples.
  double weight = 20;
  // A photo's mask is not trusted within this many pixels of a fitted point
  // that projects outside it (the mask missed part of the page there).
  double doubt_radius_px = 25;
  // A photo whose mask this share of the fitted points projects outside is
  // not used at all.
  double max_points_outside = 0.02;
  // Vertices on a lattice of about this many rows along M's longer side
  // (the first round's grid), whatever the subdivision.
  int lattice_rows = 31;
};

// One photo's page mask prepared for HullMarkers, at `scale` times the
// photo's size (maps index scaled pixels; distances are in photo pixels).
struct HullView {
  PinholeCamera camera;
  std::array<double, 4> distortion{};
  double scale = 1;
  cv::Mat1f outside;  // distance to the page, photo pixels (0 inside)
  cv::Mat1f dx, dy;   // its gradient
  cv::Mat1b doubt;    // non-zero: the mask is not trusted here
};

// The masks at most `max_side` pixels on their longer side (a 48-megapixel
// photo's distance map would take 700 MB).
std::vector<HullView> PrepareHullViews(const std::vector<ViewPage>& pages, int max_side = 1600);

// How far the fitted points agree with one photo's mask.
struct HullViewCheck {
  std::string image;
  int points_seen = 0;     // projecting into the photo
  int points_outside = 0;  // of those, more than outside_px outside its mask
  bool used = true;        // false: more than max_points_outside of them
};

// Marks, in every view, where the fitted points project outside its mask
// (HullView::doubt); a view with too many such points is not used at all.
std::vector<HullViewCheck> MarkMaskDoubts(const std::vector<Eigen::Vector3d>& points,
                                          const HullOptions& options, std::vector<HullView>* views);

// The reference page shrunk by page_inset_px: where page vertices project.
cv::Mat1b PageInterior(const cv::Mat1b& reference_page, const HullOptions& options);

// Markers (line -1, with `across`, weight `options.weight`) for every page
// vertex of `meshes` (projecting into `page_interior` in the reference) that
// projects more than outside_px outside some view's mask, where trusted.
std::vector<isometry::Marker> HullMarkers(const MeshPair& meshes, const PinholeCamera& reference,
                                          const cv::Mat1b& page_interior,
                                          const std::vector<HullView>& views,
                                          const HullOptions& options);

}  // namespace docunfold::optimize
