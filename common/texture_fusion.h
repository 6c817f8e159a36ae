// Texture for a surface from every photo that sees it (multi-view texture
// fusion, after Waechter, Moehrle and Goesele, "Let There Be Color!", 2014):
// each output pixel is a point of a triangle mesh; every photo in which that
// point is in front of the camera, inside the frame and the photo's page
// mask, not hidden by the surface itself (a depth buffer) and seen from the
// same side as the first photo sees it, is a candidate. The steps:
//  1. every photo renders the whole surface into the output frame, with its
//     resolution there (the smaller singular value of output pixel -> photo
//     pixel: how finely the photo resolves the worse direction);
//  2. each photo's brightness and white balance are levelled to the first
//     photo's by a smooth per-channel gain field fitted on their overlap;
//  3. what remains of misregistration between the photos (the surface is
//     never exact) is taken out by optical flow onto the first photo's
//     rendering on the overlap, carried smoothly over the rest;
//  4. a labelling of texel patches (alpha-expansion graph cuts) picks one
//     photo per patch: resolution (scaled down for a shaken or out-of-focus
//     photo, whose print is blurred), a preference for the first photo (the
//     frame everything is registered to), a penalty for a photo much
//     brighter than the others there (glare); seams cost where the photos
//     disagree, so they run where they agree;
//  5. a blend a few pixels wide across each seam.
// The first view is the reference: its side of the surface is the printed
// one, the others are levelled and registered to it.
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/raster.h"

namespace docunfold {

// One photo to texture from.
struct FusionView {
  PinholeCamera camera;  // in the surface's world frame
  // OpenCV's k1 k2 p1 p2 of `photo` (zeros: an undistorted image).
  std::array<double, 4> distortion{};
  cv::Mat photo;   // 8-bit BGR, camera.width x camera.height
  cv::Mat1b mask;  // non-zero = page; empty = the whole frame
  std::string name;
};

// The surface and the output frame: vertex i of `world` appears at output
// pixel `pixel[i]` (pixel centres at integers). The map from the output to
// the surface is affine on each triangle (a flat page, M' or (s, t)).
struct FusionSurface {
  std::vector<Eigen::Vector3d> world;
  std::vector<Eigen::Vector2d> pixel;
  std::vector<Triangle> triangles;
  int width = 0, height = 0;
};

struct FusionOptions {
  // A photo resolves an output pixel fully at this many photo pixels per
  // output pixel (in the worse direction); finer adds nothing to the
  // choice, coarser costs log(cap / resolution).
  double resolution_cap = 1.0;
  // The reference photo keeps a patch unless another resolves it this many
  // times better (1: any photo that resolves it better). The others are
  // registered and levelled to it, and seams run where the photos agree:
  // at 1.5 the bench's MS-SSIM was a little lower and its CER higher
  // (docs/decisions/render.md, "Every photo that resolves a part better").
  double reference_preference = 1.0;
  // A photo blurred (shaken, out of focus) resolves less than its pixels
  // say: its resolution is scaled by its sharpness against the sharpest
  // photo, measured by squared grey gradients where two photos resolve the
  // surface within this ratio of each other...
  double sharpness_resolution_band = 1.25;
  // ...and over which the mean squared gradient (grey levels², Sobel) is at
  // least this (less: blank paper, whose noise says nothing)...
  double sharpness_min_energy = 100;
  // ...and a view within this ratio of the sharpest counts as sharp; past
  // it, each e-fold of gradient energy it lacks costs blur_weight e-folds of
  // resolution (the energy of upsampled print falls about as fast as the
  // resolution, but a shaken photo's smear reads worse than a coarse one).
  double sharpness_tolerance = 1.5;
  double blur_weight = 2.0;
  // Side of a texel patch, output pixels (the labelling's unit).
  int patch_px = 8;
  // Weight of a seam's cost (the photos' colour difference across it, 0..1
  // per channel) against the data costs (log resolution ratios).
  double seam_weight = 2.0;
  // Outliers (brightness after levelling, blurred over a few pixels): where
  // three or more photos see a point, one that differs from their median by
  // more than outlier_ratio (glare, the table past a misplaced page edge, a
  // shadow); where two do, the brighter when it is brighter by more than
  // glare_ratio (glare only adds light). Cost per pixel of either.
  double outlier_ratio = 0.2;
  double glare_ratio = 0.12;
  double outlier_cost = 4.0;
  // Where the reference sees a point too, another photo whose detail there
  // differs from the reference's by more than this (mean absolute grey
  // difference, 0..1, over ~10 output pixels after a blur of 2) pays
  // outlier_cost: the surface is off there and the photo shows some other
  // part of the page.
  double reference_disagreement = 0.08;
  // Within this fraction of the output's diagonal from the surface's border,
  // a point the reference sees is coloured from it: the border was drawn on
  // the reference's outline, and the other photos see the table there as
  // soon as the surface is a little off.
  double reference_border = 0.01;
  // Width of the blend across seams, output pixels (Gaussian sigma).
  double blend_sigma = 2.0;
  // Gain fields: one gain per block of this many output pixels, smoothed
  // over a few blocks; a spot smaller than about two blocks (glare) does not
  // bend them.
  int gain_block_px = 32;
  // Flow onto the reference (off only to measure what it buys).
  bool register_views = true;
  // The longest flow kept, as a fraction of the output's diagonal; larger
  // flow means the photos disagree on more than misregistration.
  double max_flow = 0.02;
  // Pre-filter when minifying (TextureSampler).
  bool antialias = true;
};

// Per view: what it contributed.
struct FusionViewReport {
  std::string name;
  double seen = 0;   // fraction of the surface's pixels it sees
  double share = 0;  // fraction of them it coloured (its label)
  // Mean gain per channel (B, G, R) over the pixels it sees (1 for the
  // reference).
  cv::Vec3d gain = cv::Vec3d(1, 1, 1);
  double flow_p95 = 0;  // 95th percentile of its flow onto the reference, px
  // Its sharpness against the sharpest photo (1: as sharp; below: blurred),
  // the factor its resolution was scaled by.
  double sharpness = 1;
};

// Labels in FusedTexture::label beyond view indices.
inline constexpr uchar kFusionUnseen = 254;   // on the surface, no photo sees it
inline constexpr uchar kFusionOutside = 255;  // not on the surface

struct FusedTexture {
  cv::Mat3b image;     // width x height; black where no photo sees the surface
  cv::Mat1b label;     // view index, kFusionUnseen or kFusionOutside
  cv::Mat1b seen;      // 255 where some photo sees the surface
  cv::Mat1b minified;  // 255 where the chosen photo was pre-filtered
  long surface_pixels = 0;
  double unseen = 0;  // fraction of the surface's pixels no photo sees
  std::vector<FusionViewReport> views;
  std::vector<std::pair<std::string, double>> timings;  // seconds per step
};

// Textures `surface` from `views` (views[0]: the reference). Views whose
// photo is empty are skipped.
FusedTexture FuseTexture(const FusionSurface& surface, const std::vector<FusionView>& views,
                         const FusionOptions& options = {});

// The labels as colours (LabelColour per view, grey where unseen, black off
// the surface), for a report.
cv::Mat3b DrawLabels(const cv::Mat1b& label);
// The colour (BGR) DrawLabels gives view `view`'s pixels.
cv::Vec3b LabelColour(int view);

}  // namespace docunfold
