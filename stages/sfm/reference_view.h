// Automatic choice of the reference view: the registered view that sees the
// whole page inside the picture and resolves its worst-seen part best.
#pragma once

#include <Eigen/Core>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "stages/sfm/colmap_model.h"

namespace docunfold::sfm {

struct ViewScore {
  std::string image;
  uint32_t image_id = 0;
  int points_seen = 0;  // 3D points this view observes
  // |cos| of the angle between the viewing ray and the local surface normal
  // of the point cloud (1 = head-on): the median over the page's points in
  // the image, weighted by the area each point stands for as the view sees
  // it, so it measures the page as a picture would (not the points this
  // view happened to match, which favour the panels facing it).
  double frontality = 0;
  // Fraction of the page's points that project inside this image with a
  // margin; below 1 the page is cut off by the image border.
  double coverage = 0;
  // Area of the page in the image, pixels (from the points' patches): how
  // much detail the view has.
  double page_pixels = 0;
  // Pixels per unit of page length in the most foreshortened direction,
  // f·cos/depth, at the `resolution_quantile` over the page's area (parts
  // outside the picture or seen from behind count 0): how sharp the
  // rectified page can be where this view sees it worst.
  double resolution = 0;
  // Fraction of the page's area this view sees from behind (a curled corner
  // turned away from it).
  double hidden = 0;
  double score = 0;  // see ScoreReferenceViews
};

struct ReferenceOptions {
  int normal_neighbours = 12;        // points in each local plane fit
  double margin_fraction = 0.02;     // of the image's short side
  double resolution_quantile = 0.1;  // of ViewScore::resolution
  // Each unit of ViewScore::hidden costs this much of the score (1 % hidden
  // = 10 % off). A part seen from behind cannot be textured from the view,
  // and the points understate it: a curled corner has few points where it
  // turns away (see docs/decisions/sfm.md, "Reference view: the hidden
  // penalty"). Normal noise puts 0.1-0.4 % on every view.
  double hidden_penalty = 10.0;
};

// Which points are the page's: a textured table gives COLMAP as many points
// as the page (often far more), and they must not decide which view shows
// the page best. Light points fall inside the rough paper mask
// (RoughPageMask) of at least half the views that see them. The others are
// the page's shaded side or the table: the table is the dominant plane among
// them when it reaches well beyond the light points' footprint (1.5x its
// area); then those not rising 5 % of the page's size above it are dropped
// (the page's flat parts are light; its shaded side stands up from the
// table); with a plain background nothing is. Without masks, or with fewer than 30 light points,
// the points seen by at least half of the views are taken instead (the page
// is what every photo aims at). `masks` maps image names to masks of any
// size (scaled to the photo).
std::vector<bool> PagePoints(const ColmapModel& model,
                             const std::map<std::string, cv::Mat1b>& masks);

// The score of one view (see ScoreReferenceViews).
double ReferenceScore(const ViewScore& view, double max_resolution,
                      const ReferenceOptions& options = {});

// Scores every registered view, best first, on the page's points:
//   score = coverage^4 * resolution / max resolution * frontality
//           * max(0, 1 - hidden_penalty * hidden)
// coverage dominates (a page cut off by the border cannot be rectified
// whole), then the resolution of the worst-seen tenth of the page. Not the
// median frontality alone: a view square to one panel of a folded page often
// sees the other panel nearly edge-on, and that panel's smeared texture and
// thin sliver of image decide the result. Measured by running the pipeline
// with every view as reference (see docs/decisions/sfm.md, "Reference
// view"). The frontality factor settles near ties: the resolution is
// estimated only where there are points, and a slanted view that alone sees
// a band of the page frontally has no point there.
std::vector<ViewScore> ScoreReferenceViews(const ColmapModel& model,
                                           const std::map<std::string, cv::Mat1b>& masks = {},
                                           const ReferenceOptions& options = {});

// A rough mask of the page in a photo: paper is light and colourless
// (Lab lightness minus twice the chroma, Otsu threshold, the convex hull of
// the largest component). Empty when implausible (under 1 % or
// over 95 % of the image). Only for telling page points from table points.
cv::Mat1b RoughPageMask(const cv::Mat& bgr);

// Unit normals of the point cloud by a plane fit through each point's
// nearest neighbours (sign arbitrary), and optionally the squared distance
// to the farthest of them (the area a point stands for). For tests too.
std::vector<Eigen::Vector3d> EstimateNormals(const std::vector<Eigen::Vector3d>& points,
                                             int neighbours,
                                             std::vector<double>* spacing2 = nullptr);

}  // namespace docunfold::sfm
