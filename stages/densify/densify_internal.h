// What the parts of densify share: the working copies of the photos, the
// triangulation helpers, and the steps Run takes (texture points in
// texture_points.cc; outline and shading-step points, which share the
// epipolar matcher, in edge_points.cc; outline points from the sides' lines
// in side_line_points.cc).
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "common/camera.h"
#include "common/depth_field.h"
#include "common/image_sampling.h"
#include "common/page_files.h"
#include "common/ply.h"
#include "common/point_source.h"
#include "common/raster.h"
#include "stages/densify/densify.h"

namespace docunfold::densify::detail {

// Bilinear sample of a float image; 0 outside its pixel centres.
inline float SampleOrZero(const cv::Mat1f& m, double x, double y) {
  return InsideImage(m, x, y) ? SampleBilinear(m, x, y) : 0.f;
}

// A photo as the stage works on it: undistorted, resized, with its camera
// and the gradient of a slightly blurred copy (grey levels per pixel).
struct View {
  int index = -1;  // in the camera set
  PinholeCamera camera;
  cv::Mat1b grey;
  cv::Mat1f gx, gy;

  Eigen::Vector2d Gradient(const Eigen::Vector2d& p) const {
    return {SampleOrZero(gx, p.x(), p.y()), SampleOrZero(gy, p.x(), p.y())};
  }
  bool Inside(const Eigen::Vector2d& p, double border = 1) const {
    return p.x() >= border && p.y() >= border && p.x() <= grey.cols - 1 - border &&
           p.y() <= grey.rows - 1 - border;
  }
};

// The working copy of a photo: resized by `scale`, undistorted.
View MakeView(int index, const PinholeCamera& camera, const cv::Mat& grey_photo,
              const std::array<double, 4>& distortion, double scale);

// A pixel of an image in a copy resized by `scale` (cv::resize's centres).
Eigen::Vector2d ScalePixel(const Eigen::Vector2d& p, double scale);

struct Observation {
  const PinholeCamera* camera;
  Eigen::Vector2d pixel;
};

// Appends a point made by densify with its PLY properties (Run sets up
// track_length, reprojection_error and source, in that order).
void AppendPoint(const Eigen::Vector3d& X, const std::array<uint8_t, 3>& rgb, int views,
                 double reprojection_error, PointSource source, PlyData* points);

// Triangulates and checks: in front of every camera, every reprojection
// within `max_error`, rays at least `min_angle` apart. Returns false when not.
bool TriangulateChecked(const std::vector<Observation>& obs, double max_error, double min_angle_rad,
                        Eigen::Vector3d* point, double* mean_error);

// --- texture points (texture_points.cc) -------------------------------------

// Structure-tensor minimum eigenvalue (7 x 7) of `grey` (corner strength:
// print has it, blank paper and straight edges little), and in `threshold`
// `fraction` of its 95th percentile over `region`. Empty when `region` is.
cv::Mat1f CornerStrength(const cv::Mat1b& grey, const cv::Mat1b& region, double fraction,
                         double* threshold);

// The depth the `known` points give each pixel of `camera` (DepthField,
// planar over the `neighbours` nearest, RBF scale `scale_px`); nullptr with
// fewer than 16 of them in front of it.
std::unique_ptr<DepthField> SurfaceOfPoints(const PinholeCamera& camera,
                                            const std::vector<Eigen::Vector3d>& known,
                                            int neighbours, double scale_px);

// A textured sample of the reference view and where the flow found it in
// the other views; `done` once it is triangulated.
struct Track {
  Eigen::Vector2d pixel;
  std::vector<Observation> obs;
  bool done = false;
};

// First pass: the textured samples of `region` followed into every other
// view through the homography of the page's SfM points (`region_points`),
// triangulated where enough views have them; appends the points (colour
// from the full-size `reference_bgr`) and counts them in `result`. Returns
// the samples, for the second pass.
std::vector<Track> AddTexturePoints(const View& ref, const std::vector<View>& others,
                                    const cv::Mat1b& region,
                                    const std::vector<Eigen::Vector3d>& region_points,
                                    const cv::Mat& reference_bgr, const TextureOptions& o,
                                    DensifyResult* result);

// Second pass: the samples the first left without a point, in the holes it
// left (TextureOptions::surface_hole_px), followed again with every view
// brought onto the reference through the surface of the `known` points.
void AddSurfaceTexturePoints(const View& ref, const std::vector<View>& others,
                             const cv::Mat1b& region, const std::vector<Eigen::Vector3d>& known,
                             const cv::Mat& reference_bgr, const TextureOptions& o,
                             std::vector<Track>* tracks, DensifyResult* result);

// --- swept points (swept_points.cc) -----------------------------------------

// Points on the print of `page` that no point is near yet, found by sweeping
// depth around the surface of `known` points (over `region`) and checked in
// the other views (SweepOptions); appended to result->points.
void AddSweptPoints(const View& ref, const std::vector<View>& others, const cv::Mat1b& region,
                    const cv::Mat1b& page, const std::vector<Eigen::Vector3d>& known,
                    const cv::Mat& reference_bgr, const SweepOptions& o, DensifyResult* result);

// --- outline and shading-step points (edge_points.cc) ------------------------

// Strongest step of sign `sign` (grey rising along +n) within +-reach of c
// along the unit normal n; returns its offset (sub-pixel) and strength.
bool FindStep(const View& view, const Eigen::Vector2d& c, const Eigen::Vector2d& n, double reach,
              int sign, double* offset, double* strength);

// The depth along the reference ray through `pixel` at which its projection
// crosses the edge found in each other view (obs[1...], edge normals
// `normals`), by Gauss-Newton from *depth: residuals across the edge only
// (along it a match is no evidence), so a view whose edge nearly follows its
// epipolar line weighs little. False when the fit fails; else the largest
// and mean absolute residual (pixels), and, when `residuals` is given, each
// view's signed residual.
bool DepthAcrossEdges(const PinholeCamera& ref, const Eigen::Vector2d& pixel,
                      const std::vector<Observation>& obs,
                      const std::vector<Eigen::Vector2d>& normals, double* depth, double* worst,
                      double* mean, std::vector<double>* residuals = nullptr);

// A crossing of an edge found in another view: where, and the edge's unit
// normal there (from that image's gradient).
struct EdgeMatch {
  Eigen::Vector2d pixel;
  Eigen::Vector2d normal;
};

struct EdgeSample {
  Eigen::Vector2d pixel;   // on the edge, reference working copy
  Eigen::Vector2d normal;  // unit, pointing out of the page
  int sign = 1;            // grey rises (+1) or falls (-1) going out
  int side = -1;           // the boundary side it is on (outline samples)
  bool matched = false;    // a point was made of it (matching or the side lines)
  double near_depth = 0, far_depth = 0;
  std::vector<std::vector<EdgeMatch>> candidates;  // per view index
};

// A sample's epipolar segment in `view`: its ray between its near and far
// depth, projected, and the direction across the edge there (its outward
// normal as `view` sees it at mid depth, unit). nullopt where the segment
// runs behind the camera or the direction is undefined.
struct EpipolarSegment {
  Eigen::Vector2d near, far, across;
};
std::optional<EpipolarSegment> EpipolarSegmentIn(const View& ref, const View& view,
                                                 const EdgeSample& e);

// Whether a triangulated edge sample at `depth` (reference camera) may be kept.
using EdgeCheck = std::function<bool(const EdgeSample&, double depth)>;

// Pixels and depths in `camera` of `page_points` and of the points made so far
// (`points` from `first_new` on): what the edge matching searches around.
void KnownPoints(const PinholeCamera& camera, const std::vector<Eigen::Vector3d>& page_points,
                 const PlyData& points, size_t first_new, std::vector<Eigen::Vector2d>* pixels,
                 std::vector<double>* depths);

// Points on the real sides of `boundary` (reference pixels; `page` is the
// document region in working-copy pixels), matched in the other views.
void AddOutlinePoints(const View& ref, const std::vector<View>& others, int num_views,
                      const Boundary& boundary, const cv::Mat1b& page,
                      const std::vector<Eigen::Vector2d>& known_pixels,
                      const std::vector<double>& known_depths, const OutlineOptions& o,
                      DensifyResult* result);

// --- outline points from the sides' lines (side_line_points.cc) -------------

// Outline points of straight real sides whose `samples` the epipolar
// matching left (not `matched`), from the sides' straight images in
// `others`; marks the samples it places and counts them in `counts`.
void AddSideLinePoints(const View& ref, const std::vector<View>& others,
                       std::vector<EdgeSample>* samples, const OutlineOptions& o,
                       const EdgeCheck& check, EdgeCounts* counts, PlyData* points);

// Points on the shading steps of blank paper inside `page`, matched like the
// outline (whose matching options `outline` gives) on blurred copies.
void AddStepPoints(const View& ref, const std::vector<View>& others, int num_views,
                   const cv::Mat1b& page, const std::vector<Eigen::Vector2d>& known_pixels,
                   const std::vector<double>& known_depths, const StepOptions& so,
                   const OutlineOptions& outline, DensifyResult* result);

}  // namespace docunfold::densify::detail
