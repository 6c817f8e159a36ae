// baseline: the reference methods of the benchmark, each a rectified image
// to evaluate beside docunfold's.
//  - homography: the reference view warped by the four detected page corners
//    onto a rectangle of the page's aspect (what a phone scanner app does);
//  - oracle: the page textured from the reference photo through the TRUE
//    surface and TRUE camera (the ceiling for any single-view texturing);
//    cropped to the part of the page some photo sees (`crop_to_seen`), the
//    ceiling for a method that cannot know how far a cut-off page goes;
//  - oracle-multiview: the true surface textured from every photo through
//    the true cameras by render's texture fusion (common/texture_fusion.h):
//    the ceiling for texturing from all the photos.
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/option_table_fwd.h"
#include "common/ply.h"
#include "common/texture_fusion.h"

namespace docunfold::baseline {

namespace fs = std::filesystem;

// Page corners in an image: top-left, top-right, bottom-right, bottom-left.
using Corners = std::array<Eigen::Vector2d, 4>;

// Width / height of the planar rectangle whose image is `corners` under a
// camera with intrinsics K (Zhang & He, "Whiteboard scanning and image
// enhancement", 2007). Falls back to the ratio of mean opposite side lengths
// when the quadrilateral is nearly a parallelogram (no perspective to use).
double AspectFromCorners(const Corners& corners, const Eigen::Matrix3d& K);

// Warps `image` so that `corners` land on the corners of an output image of
// `size` (page edges on the outer pixel borders). Bicubic; when the output
// is smaller than the page in the image, it is rendered larger and area-
// averaged down so that text does not alias.
cv::Mat WarpByCorners(const cv::Mat& image, const Corners& corners, cv::Size size);

// Textures the flat page (size of flat.png) from `photo` through the true
// surface: `mesh` has per-vertex s, t (column/row fractions of flat.png) and
// vertices in the world frame of `camera`. Bicubic, area-averaged when the
// photo is minified. Throws InputError when the mesh lacks s, t.
cv::Mat TextureFromTruth(const cv::Mat& photo, const PinholeCamera& camera, const PlyData& mesh,
                         cv::Size size);

// Pixel rectangle of the flat page rendered at `size` that holds every point
// of the true surface inside the frame of at least one of `cameras` (and in
// front of it; the page hiding part of itself is not considered). All of
// `size` when some photo sees each part of the page; empty when none sees
// any. `mesh` as for TextureFromTruth.
cv::Rect SeenPageRect(const std::vector<PinholeCamera>& cameras, const PlyData& mesh,
                      cv::Size size);

// The true surface textured from `photos` (views[0]: the reference)
// through their true cameras by texture fusion; where no photo sees the
// page, the median colour of the rest (the paper). `mesh` as for
// TextureFromTruth.
FusedTexture FuseFromTruth(const std::vector<FusionView>& views, const PlyData& mesh,
                           cv::Size size);

enum class Method { kHomography, kOracle, kOracleMultiview };

struct BaselineOptions {
  Method method = Method::kHomography;
  // Output width in pixels, the height following from the page's aspect.
  // 0 = the size of ground_truth/flat.png when the data set has one, else
  // (homography only) the mean length of the page's top and bottom sides in
  // the reference view.
  int width = 0;
  // --shading remove: divide out the light's shading afterwards
  // (common/shading.h), as render --shading remove does: the ceiling for
  // results rendered that way.
  bool remove_shading = false;
  // Oracles: keep only SeenPageRect over all true cameras. Where no photo
  // sees some part of the page (cut-off pages), no method working from the
  // photos can know where the page ends: the plain oracle knows it from the
  // true surface. The same image as the plain oracle on a page seen whole.
  bool crop_to_seen = false;
  // Homography: turn the page clockwise by this many quarter turns (render's
  // orientation.quarter_turns_clockwise in 60_render/render.json), so that
  // it reads the same way up as docunfold's result, as a scanner app's page
  // would. The corners' labels come from segment-boundary, which tells up
  // from down only when it can read the text.
  int quarter_turns = 0;
};

// Declares every option of BaselineOptions (--method is required).
void DeclareOptions(OptionTable& table, BaselineOptions* options);

struct BaselineInputs {
  fs::path data;  // data set (images/, ground_truth/)
  fs::path work;  // work directory (10_sfm/, 20_boundary/)
};

struct BaselineResult {
  cv::Mat image;
  std::string summary;  // one line: what was done, the size and aspect
};

// Reads what the method needs (throws InputError naming a missing or bad
// file) and makes the image.
BaselineResult Run(const BaselineInputs& inputs, const BaselineOptions& options);

}  // namespace docunfold::baseline
