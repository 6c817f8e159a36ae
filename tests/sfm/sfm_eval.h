// Measuring an sfm output (10_sfm/) against a data set's ground truth: camera
// centres and points after a similarity alignment, how frontal and complete
// the chosen reference view is, and small helpers for the sfm tests.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/ply.h"
#include "tests/support/ground_truth.h"

namespace docunfold::testing {

namespace fs = std::filesystem;

// samples/* and ../shared/realistic/* with ground_truth/cameras.json, sorted.
std::vector<fs::path> SfmDataSets();
// "realistic/r01" or "samples/set03".
std::string SfmDataSetName(const fs::path& dataset);

// How a true camera sees the page.
struct TrueViewFigures {
  std::string image;
  // Median over the page's pixels in the view of |cos| of the angle between
  // the viewing ray and the true surface normal (1 = head-on).
  double frontality = 0;
  // Pixels per unit of page length across the foreshortening (f·cos/depth),
  // 10 % quantile over the page's area, hidden or out-of-picture parts 0:
  // what sfm's reference score estimates from the points.
  double resolution = 0;
  bool whole_page = false;  // the page touches no image border
};
std::vector<TrueViewFigures> TrueViews(const GroundTruth& gt);

struct SfmFigures {
  int views = 0;          // photos in the data set (true cameras)
  int registered = 0;     // views in cameras.json that have a true camera
  double camera_rms = 0;  // RMS camera-centre error, fraction of the diagonal
  int points = 0;
  int page_points = 0;              // points on the true page in most views they fall in
  double median_page_distance = 0;  // median distance of those to the surface, fraction
  double median_all_distance = 0;   // same over every point
  // Median distance of the page points after fitting them to the surface by
  // a similarity (ICP): the shape alone, without the camera error.
  double shape_median_distance = 0;
  // The same ICP with the camera pairs of the alignment above in the fit,
  // weighing as much as the points: the similarity that fits cameras and
  // page together, and the camera-centre RMS and page points' median
  // distance under it (fractions of the diagonal).
  double joint_camera_rms = 0;
  double joint_median_distance = 0;
  std::string reference;
  double reference_frontality = 0;  // true figures of the chosen reference
  double reference_resolution = 0;
  bool reference_whole_page = false;
  std::string best_true_view;  // best-resolving true view that sees the whole page
  double best_true_resolution = 0;
  double reference_median_depth = 0;  // of the points inside the reference image
};

// Reads <sfm_dir>/cameras.json and points.ply and measures them. Alignment:
// Eigen::umeyama of the sfm camera centres onto the true ones; distances are
// exact point-to-triangle distances to the true mesh.
SfmFigures MeasureSfm(const fs::path& sfm_dir, const GroundTruth& gt);

std::string FormatFigures(const SfmFigures& f);

// Closest distance from `p` to triangle (a, b, c).
double PointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                             Eigen::Vector3d* closest = nullptr);

// A copy of `dataset`'s photos (the first `count`, scaled to `width` pixels
// wide, as JPEG) in <dir>/images; returns dir. For small, fast fixtures.
fs::path MakeSmallDataSet(const fs::path& dataset, const fs::path& dir, int count, int width);

// The first data set with truth found, or "" (tests skip then).
fs::path AnyDataSet();

}  // namespace docunfold::testing
