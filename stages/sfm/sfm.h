// sfm: cameras and a sparse point cloud from the photos of a data set, by
// COLMAP's command-line tools (CPU SIFT, every pair matched exactly by
// matching.h and verified by COLMAP, incremental mapper), expressed in the
// frame of an automatically chosen reference view (reference_view.h).
//
// Writes into options.out_dir (all or nothing: everything is made in a
// temporary directory beside it and renamed into place at the end):
//   cameras.json   docunfold.cameras v1: reference image name; per registered
//                  view image, width, height, K, R, t (x_cam = R x_world + t,
//                  world = reference camera frame scaled so that the median
//                  depth of the points the reference sees is 1)
//   points.ply     binary PLY: x y z, red green blue, track_length,
//                  reprojection_error (pixels)
//   reference.png  the reference photo (upright), undistorted when the camera
//                  model has distortion; its K is the one in cameras.json
//   colmap/        images/ (the photos' copies COLMAP saw, photo_set.h),
//                  database.db, sparse/0/*.bin (COLMAP's binary model),
//                  *.log (everything COLMAP printed)
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/json_io.h"
#include "common/option_table_fwd.h"
#include "stages/sfm/photo_set.h"
#include "stages/sfm/reference_view.h"

namespace docunfold::sfm {

namespace fs = std::filesystem;

struct SfmOptions {
  fs::path data_dir;      // data set folder (with images/)
  fs::path out_dir;       // e.g. work/set01/10_sfm
  std::string reference;  // image name forcing the reference view ("" = auto)

  // Long side (pixels) of the copies COLMAP works on (photo_set.h); its
  // cameras are taken back to each photo's full resolution. 1600 keeps the
  // 1600x1200 sets at full resolution and brings 4000x3000 photos down to the
  // same detail per page.
  int max_image_size = 1600;
  int max_num_features = 8192;  // per image
  // COLMAP camera model shared by all views: SIMPLE_PINHOLE, PINHOLE,
  // SIMPLE_RADIAL or RADIAL. The default SIMPLE_RADIAL with the tight
  // reprojection filter below kept the shape best on our data (see
  // docs/decisions/sfm.md, "Camera model and mapper filter").
  std::string camera_model = "SIMPLE_RADIAL";
  // Refine the distortion parameters in bundle adjustment (otherwise they
  // stay 0 and a *_RADIAL model behaves as a pinhole one).
  bool refine_distortion = true;
  // Observations farther than this from their point's projection are
  // dropped by the mapper, in pixels of the images SIFT ran on (scaled up to
  // full resolution for COLMAP). COLMAP's default is 4.
  double max_reprojection_error = 1.0;
  // Triangulate points seen by only two views too (COLMAP ignores them by
  // default, which suits large collections; with 3-6 photos they are a
  // third of the data and pin the focal length down better: see
  // docs/decisions/sfm.md, "Two-view tracks").
  bool two_view_tracks = true;
  // When the first reconstruction is implausible (views left out, a focal
  // length outside focal_range, too few points), retry with the other
  // distortion setting and with COLMAP's default filter; keep the best. Two
  // photos without EXIF whose focal length no phone's main camera has are
  // retried at a phone's instead (colmap_steps.cc).
  bool retry = true;
  // Plausible focal lengths as multiples of the image's long side (a 10x
  // telephoto to a 120-degree wide angle).
  double min_focal_factor = 0.3;
  double max_focal_factor = 10.0;

  // "exact": every pair's SIFT matches by brute force under COLMAP's
  // criteria (matching.h), verified by COLMAP's matches_importer: the same
  // photos give the same cameras and points on every run. "colmap": COLMAP's
  // exhaustive_matcher, whose FLANN search differs a little from run to run.
  std::string matcher = "exact";

  int min_points = 100;           // fewer 3D points: bad input (exit 3)
  int threads = -1;               // COLMAP threads (not the mapper's); -1 = all cores
  double timeout_seconds = 900;   // per COLMAP command
  std::string colmap = "colmap";  // COLMAP executable (name in PATH or path)
  bool verbose = false;           // echo COLMAP's output lines on stderr

  ReferenceOptions reference_options;  // not on the command line
};

// Declares the options of `o` that are flags of `sfm` (all but the paths,
// the focal range and reference_options), bound to its fields.
void DeclareOptions(OptionTable& table, SfmOptions* o);

// One run of COLMAP's mapper.
struct MapperAttempt {
  std::string description;  // e.g. "SIMPLE_RADIAL, distortion refined, filter 1 px"
  bool produced_model = false;
  int registered = 0;
  int points = 0;
  double mean_reprojection_error = 0;
  double focal = 0;            // pixels
  std::vector<double> params;  // COLMAP's camera parameters
  bool plausible = false;
  std::string problem;  // why not plausible
  double seconds = 0;
};

struct SfmResult {
  std::string reference;         // image name
  std::string reference_choice;  // "auto" or "--ref"
  CameraSet cameras;             // every registered view, reference frame
  // Distortion (OpenCV k1, k2, p1, p2 on normalized coordinates) of each
  // registered photo; all zero for pinhole models. reference.png is
  // undistorted.
  std::map<std::string, std::array<double, 4>> distortion;
  std::string camera_model;  // COLMAP model name
  PhotoSet photos;           // the photos as COLMAP saw them; what was left out
  // COLMAP's cameras (one per CameraGroup that has a registered photo), by
  // group index: their parameters, in the copies' pixels.
  std::map<int, std::vector<double>> colmap_params;
  std::vector<std::string> unregistered;
  // Of those, the photos the mapper was not given: no verified matches link
  // them to the mapped ones (another page, or a photo of something else).
  std::vector<std::string> not_mapped;
  // Of those, the groups of two or more linked among themselves: other pages
  // (each sorted by name; the groups by their first name).
  std::vector<std::vector<std::string>> other_pages;
  std::vector<Eigen::Vector3d> points;  // reference frame
  std::vector<std::array<uint8_t, 3>> colors;
  std::vector<int> track_lengths;
  std::vector<double> reprojection_errors;  // pixels of the copies COLMAP saw
  double mean_reprojection_error = 0;
  // Median depth (COLMAP's units) of the points the reference view sees:
  // the frame was divided by it.
  double scale_divisor = 1;
  std::vector<ViewScore> view_scores;  // best first
  int page_points = 0;                 // points the scores were computed on
  std::vector<MapperAttempt> attempts;
  double seconds_reading = 0, seconds_extracting = 0, seconds_matching = 0, seconds_mapping = 0,
         seconds_total = 0;
};

// Runs the whole stage and writes the outputs, `options_record` as
// cameras.json's producer options. Throws InputError (bad data set, image or
// --ref; too few views registered or points), OutputError (cannot write),
// std::runtime_error (COLMAP missing or failing).
SfmResult RunSfm(const SfmOptions& options, const Json& options_record);

// --- building blocks (exposed for tests) ----------------------------------

// The cameras and points of `model` in the frame of `reference`: each camera
// in its own photo's pixels (`photos`, ToPhotoFrame), the reference camera's
// rotation and translation removed, scaled so that the median depth of the
// points the reference sees is 1. Returns the divisor used.
double ToReferenceFrame(const ColmapModel& model, const PhotoSet& photos,
                        const std::string& reference, CameraSet* cameras,
                        std::vector<Eigen::Vector3d>* points);

// The photo as the pinhole camera `K` would have taken it (same size, same
// K); a copy when there is no distortion.
cv::Mat UndistortPhoto(const cv::Mat& photo, const Eigen::Matrix3d& K,
                       const std::array<double, 4>& distortion);

// The cameras.json document of a result.
Json CamerasJson(const SfmResult& result, const Json& options_record);

}  // namespace docunfold::sfm
