// densify: more 3D points on the page than COLMAP's sparse cloud, with the
// cameras sfm found held fixed. Three sources, each measured against the
// ground truth (see docs/decisions/densify.md):
//  - texture: every `step_px`-th pixel of the reference view's document
//    region with enough texture (text, print) is followed into each other
//    photo by optical flow (DIS, after a homography that takes the page's
//    SfM points across), kept when the flow agrees forwards and backwards,
//    and triangulated from at least `min_views` photos;
//  - outline: samples of the real boundary sides of 20_boundary are matched
//    along their epipolar segments in every other photo (the page's edge is
//    a sharp, straight step there too); a depth that at least two other
//    photos agree on, and no other depth does as well, is triangulated;
//  - shading steps: steps of blank paper (a fold's crease) on copies blurred
//    so that print is gone, matched like the outline;
//  - swept: print the others missed, found by sweeping depth along the
//    reference's rays around the surface of the points so far (SweepOptions).
// Blank paper gives SIFT nothing, so COLMAP's cloud leaves margins and flaps
// empty; their outline points and the text's points fill most of that.
//
// Writes into options' out_dir (each file atomically):
//   points.ply   binary PLY: sfm's points in their order, less those hidden
//                behind the page in the reference view (HiddenOptions), then
//                the new ones; x y z, red green blue, track_length,
//                reprojection_error (pixels of the working copies), source
//                (PointSource: 0 sfm, 1 texture, 2 outline, 3 step, 4 swept)
//   points.json  docunfold.points: counts, per-view statistics, options, times
//   overlay.png  the reference image with the points by source
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/json_io.h"
#include "common/option_table_fwd.h"
#include "common/page_files.h"
#include "common/ply.h"
#include "common/point_source.h"

namespace docunfold::densify {

namespace fs = std::filesystem;

struct TextureOptions {
  bool enabled = true;  // texture points at all
  double step_px = 4;   // grid spacing in working-copy pixels
  // Structure-tensor minimum eigenvalue (7x7 window) below this fraction of
  // its 95th percentile over the region: blank paper, where flow only
  // interpolates, is skipped.
  double min_texture = 0.05;
  double max_flow_disagreement_px = 0.5;  // forward + backward flow, |sum|
  double max_reprojection_px = 1.0;       // every view, working-copy pixels
  // Photos a point needs, the reference included: two-view points are much
  // less accurate (see docs/decisions/densify.md, "Texture points need three
  // photos").
  int min_views = 3;
  double min_triangulation_angle_deg = 2;
  // A second pass for the samples the first left without a point, each
  // photo brought onto the reference through the depth the points found so
  // far give every pixel (a planar fit of 1/depth to the
  // `surface_neighbours` nearest, on a grid of `surface_grid_px`) instead of
  // one homography of the page: a flap or the far side of a fold stands at
  // another angle than the panel the homography fits (see
  // docs/decisions/densify.md, "A second texture pass").
  bool surface_prewarp = true;
  double surface_grid_px = 4;
  int surface_neighbours = 16;
  // The second pass tries only samples at least this far (working-copy
  // pixels) from every point the first pass made: the holes it left (a far
  // panel), not the ragged edges of what it found. 0: every sample left.
  // Smaller gaps reach flaps seen at a grazing angle, whose points make M'
  // too long there (see docs/decisions/densify.md, "The second pass's hole
  // gap").
  double surface_hole_px = 150;
};

struct OutlineOptions {
  bool enabled = true;        // outline points at all
  double step_px = 4;         // spacing of the samples along each real side
  double corner_gap_px = 12;  // no samples this close to a corner
  double min_contrast = 3;    // grey levels per pixel across the edge (after blur)
  // The depth searched along each sample's ray: the depth range of its
  // `depth_neighbours` nearest points (sfm + texture) in the reference
  // image, widened by `depth_margin` on both sides.
  int depth_neighbours = 16;
  double depth_margin = 0.15;
  // Edges crossing the epipolar segment at less than this angle are skipped
  // (the match slides along the edge).
  double min_epipolar_angle_deg = 20;
  // A candidate must continue as a step of the same sign for this far along
  // the edge's direction on both sides: texture of a table or carpet gives
  // short gradient blobs, a page's edge a straight step.
  double straight_px = 6;
  double agree_px = 1.5;             // other views agree within this distance
  double max_reprojection_px = 1.0;  // after triangulating from all of them
  int min_views = 3;                 // the reference included
  // A point must continue the surface of the known points within
  // `continuity_radius_px` of it (an affine fit of 1/depth, when at least 6
  // are there) to `max_depth_jump` of its depth. The silhouette of a curl
  // is matched across views like an edge, but its triangulation lies off
  // the page (see docs/decisions/densify.md, "Outline points continue the
  // surface").
  double continuity_radius_px = 24;
  double max_depth_jump = 0.02;
  // Samples of a straight side left without a point get one from the side's
  // lines in the other photos (AddSideLinePoints, side_line_points.cc): the side
  // straight within side_line_max_rms_px in each (working-copy pixels),
  // with side_line_min_samples of them; steps looked for this far either
  // side of a sample's epipolar segment; a photo's plane at least
  // side_line_min_angle_deg off the reference's.
  // A photo's line is the one at least side_line_min_share of the steps
  // lie within a pixel of. A point is kept only where a bias of
  // side_line_bias_px in every line would move it at most
  // side_line_max_depth_error of its depth along its ray.
  bool side_lines = true;
  double side_line_max_rms_px = 1.0;
  int side_line_min_samples = 20;
  double side_line_reach_px = 3;
  double side_line_min_angle_deg = 2;
  double side_line_min_share = 0.3;
  double side_line_bias_px = 0.5;
  double side_line_max_depth_error = 0.003;
};

// Points on shading steps of blank paper: where a fold crosses paper without
// print nothing else gives it points, and the mesh passes over it rounded.
// Under diffuse light a fold's shading step lies at the same place on the
// paper in every photo, so steps found on copies blurred by `blur_px`
// (print gone, folds not) are matched along epipolar segments like the
// outline. The safeguards were each added after a measured failure (see
// docs/decisions/densify.md, "Shading-step points").
struct StepOptions {
  bool enabled = true;         // shading-step points at all
  double blur_px = 3;          // Gaussian sigma of the copies, working-copy pixels
  double step_px = 6;          // at most one sample per cell of this size
  double min_contrast = 1.5;   // grey levels per pixel across the step (after blur)
  double outline_gap_px = 10;  // no samples this close to the page's outline
  // Only blank paper: no samples within this distance of a point already
  // there (sfm, texture, outline). A blurred table's rules and text rows are
  // steps too; points on them, between the texture points, roughen M and
  // lengthen M' (see docs/decisions/densify.md, "Shading steps only on blank
  // paper").
  double min_point_gap_px = 20;
  // A point must lie on the surface of the known points on each side of its
  // step that has at least 6 within `side_radius_px` (an affine fit of
  // 1/depth, exact on a plane: a fold's crease lies on both panels) to
  // `max_depth_jump` of its depth, and neither side may meet the reference
  // ray at |cos| below `min_side_cos` (seen edge-on, a fold is a silhouette).
  double side_radius_px = 40;
  double max_depth_jump = 0.02;
  double min_side_cos = 0.25;
  // Points with no known points on either side (a panel without print or
  // texture points: set08's far panel) are checked against the points within
  // `unsupported_radius_factor` x the radius where there are any.
  double unsupported_radius_factor = 3;
  // Photos a point needs, the reference included. With 3, a flap seen
  // edge-on in the reference gave points off the page where no side check
  // reaches (see docs/decisions/densify.md, "Shading steps need four
  // photos"). A data set of 3 photos gets no step points.
  int min_views = 4;
};

// SfM points of the document region that the reference view shows in another
// colour are behind the page there: table seen past a raised flap by the other
// photos, not page. They are left out of points.ply (see
// docs/decisions/densify.md, "Hidden sfm points").
struct HiddenOptions {
  // CIE76 colour difference on OpenCV's 8-bit Lab scale (L 0..255), after the
  // points' colours are brought to the reference's exposure (a per-channel
  // gain, the median ratio over the region's points).
  double max_colour_distance = 40;
  int window_px = 1;  // nearest colour within this many pixels of the projection
};

// Points where no other pass reached: a panel the reference sees at a
// grazing angle shows its print squeezed, and neither the flow nor the
// edges match it. Each printed reference patch there is carried into the
// other photos through the plane of the points' own surface (DepthField,
// planar) at a series of depths along its ray and scored by NCC; in
// `rounds` rounds, each around the surface of the points so far (see
// docs/decisions/densify.md, "Swept points").
struct SweepOptions {
  bool enabled = true;  // swept points at all
  int rounds = 3;
  double step_px = 4;        // candidate grid (working-copy px)
  double min_gap_px = 12;    // candidates at least this far from every point so far
  int patch_radius = 4;      // 9 x 9 patches ...
  int edge_gap_px = 3;       // ... at least this far inside the page's mask
  double min_variance = 25;  // grey variance of the patch (grey levels squared)
  // Print, not a straight line: the structure tensor's smaller eigenvalue
  // (7 x 7) at least `min_corner` of its 95th percentile over the page, and
  // over `isotropy_window` px at least `min_isotropy` of the larger one. A
  // dashed rule or a crease is one-dimensional and its depth slides along it.
  double min_corner = 0.05;
  double min_isotropy = 0.2;
  int isotropy_window = 15;
  double depth_range = 0.15;   // swept over +- this fraction of the surface's depth
  int depth_steps = 81;        // uniform in 1/depth
  double min_ncc = 0.6;        // each of the two best photos at the peak
  int unique_steps = 3;        // no depth more than this many steps from the peak ...
  double unique_margin = 0.1;  // ... scores within this of it
  // A point's depth / surface depth within this of the median of the found
  // candidates within `neighbour_radius_px` (at least 3 of them).
  double max_ratio_deviation = 0.01;
  double neighbour_radius_px = 24;
  double visibility_slack = 0.02;  // depth-buffer tolerance in the other photos (fraction)
  int surface_neighbours = 16;     // DepthField's planar fit
  double surface_grid_px = 8;      // the surface's grid (working-copy px)
};

struct DensifyOptions {
  fs::path data_dir;  // data set folder (with images/)
  fs::path sfm_dir;   // 10_sfm/
  fs::path boundary;  // 20_boundary/ or its boundary.json
  fs::path out_dir;   // e.g. 25_points/
  // Long side of the working copies of the photos; 1600 keeps the
  // 1600x1200 sets as they are and brings 4000x3000 photos down to the
  // same detail per page.
  int max_image_size = 1600;
  double region_margin_px = 4;  // document region grown by this (reference pixels)
  TextureOptions texture;
  OutlineOptions outline;
  StepOptions steps;
  SweepOptions sweep;
  // Keep the sfm points the reference view shows in another colour
  // (HiddenOptions) instead of leaving them out.
  bool keep_hidden = false;
  HiddenOptions hidden;
};

// Declares every option of `o` but the paths (the flags of `densify`), bound
// to its fields.
void DeclareOptions(OptionTable& table, DensifyOptions* o);

struct DensifyInputs {
  CameraSet cameras;                              // every registered view, reference frame (sfm)
  std::vector<std::array<double, 4>> distortion;  // per view: OpenCV k1 k2 p1 p2
  cv::Mat reference;                              // 10_sfm/reference.png (undistorted), BGR
  std::vector<cv::Mat> photos;  // per view, greyscale as taken (empty for the reference)
  Boundary boundary;
  cv::Mat1b region;  // document region, reference pixels (mask.png)
  PlyData points;    // 10_sfm/points.ply
};

struct ViewStats {
  std::string image;
  int page_points = 0;           // sfm points of the page seen in both (homography)
  int flow_matches = 0;          // texture samples followed into this view
  int surface_flow_matches = 0;  // ... in the second pass (surface prewarp)
  int outline_candidates = 0;    // edge crossings found on the epipolar segments
  int outline_votes = 0;         // of those, in a triangulated outline point
};

// What became of the edge samples of one kind (outline or shading steps).
struct EdgeCounts {
  int samples = 0;      // edge samples matched in the other views
  int unmatched = 0;    // fewer than min_views agree
  int ambiguous = 0;    // another depth is as well supported
  int off_surface = 0;  // off the surface of the known points
  int points = 0;       // triangulated and kept
  // Of `points`, those from the sides' lines (outline only): samples the
  // epipolar matching left (unmatched, ambiguous or off the surface).
  int side_line_points = 0;
  // Samples on a side's lines left out: the lines' planes too near each
  // other there (side_line_max_depth_error).
  int side_line_weak = 0;
};

struct DensifyResult {
  PlyData points;  // sfm's points, then texture, outline and step points
  int sfm_points = 0, sfm_points_in_region = 0, texture_points = 0;
  int texture_points_surface = 0;  // of texture_points, from the second pass
  struct {
    int candidates = 0;  // reference pixels swept, over all rounds
    int points = 0;
  } sweep;
  std::vector<Eigen::Vector3d> hidden;  // sfm points left out (HiddenOptions)
  int texture_samples = 0;              // textured grid pixels in the region
  EdgeCounts outline;                   // samples on the real sides (OutlineOptions)
  EdgeCounts steps;                     // shading steps (StepOptions)
  double working_scale = 1;             // working copies / photos
  std::vector<ViewStats> views;
  double seconds_reading = 0, seconds_texture = 0, seconds_outline = 0, seconds_surface = 0,
         seconds_steps = 0, seconds_sweep = 0, seconds_total = 0;
  std::vector<std::string> warnings;
};

// Reads and checks everything Run needs (InputError names the file).
DensifyInputs ReadInputs(const DensifyOptions& options);

DensifyResult Run(const DensifyInputs& inputs, const DensifyOptions& options);

// Writes points.ply, points.json (with `options_record` as its producer's
// options) and overlay.png into options.out_dir (OutputError on failure).
void WriteOutputs(const DensifyInputs& inputs, const DensifyResult& result,
                  const DensifyOptions& options, const Json& options_record);

// --- building blocks (exposed for tests) ----------------------------------

// `camera` for a copy of its image resized by `scale` (cv::resize's pixel
// centres: x' = (x + 0.5) scale - 0.5).
PinholeCamera ScaleCamera(const PinholeCamera& camera, double scale);

// Point seen at `pixels[i]` by `cameras[i]` (linear, DLT); NaN when the rays
// are degenerate.
Eigen::Vector3d Triangulate(const std::vector<const PinholeCamera*>& cameras,
                            const std::vector<Eigen::Vector2d>& pixels);

// For each of `indices` into `points` (colours RGB), whether `reference`
// (BGR, seen by `camera`) shows no colour within options.max_colour_distance
// of the point's anywhere within options.window_px of its projection, after
// the per-channel exposure gain (median over the judged points). Points
// behind the camera or outside the image are not judged (false), nor any
// when the points have no colours or all the same one.
std::vector<bool> HiddenInReference(const std::vector<Eigen::Vector3d>& points,
                                    const std::vector<std::array<uint8_t, 3>>& colours,
                                    const std::vector<int>& indices, const PinholeCamera& camera,
                                    const cv::Mat& reference, const HiddenOptions& options);

}  // namespace docunfold::densify
