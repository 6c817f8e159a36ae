// The steps of render's Run (render.cc), for the files that implement them:
// projecting and sampling (render_pixels.cc), the sides, deskew and crop
// (render_crop.cc).
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/grid_mesh.h"
#include "common/raster.h"
#include "stages/render/crop.h"
#include "stages/render/render.h"

namespace docunfold::render {

// Output pixel states.
inline constexpr uchar kOutside = 0;        // not on M'
inline constexpr uchar kPage = 1;           // sampled from the reference image
inline constexpr uchar kHidden = 2;         // on M', but the reference view does not see it
inline constexpr uchar kOtherView = 4;      // past a cut side, from another view's photo
inline constexpr uchar kHiddenSampled = 3;  // the same, sampled anyway (--sample-hidden)

// Largest rms distance of a side's samples from its fitted line, as a
// fraction of the diagonal of M', for the side to bound the crop.
inline constexpr double kMaxSideRms = 0.005;

struct ProjectedMesh {
  std::vector<Eigen::Vector3d> cam;    // vertices in the reference camera frame
  std::vector<Eigen::Vector2d> pixel;  // their projections
  std::vector<Triangle> triangles;
  std::vector<char> front;  // triangle faces the camera like most of M
  double density = 0;       // reference pixels per unit of M'
  int faces_in_view = 0;
  RasterResult raster;  // M in the reference image: nearest triangle per pixel
};

// The page region of the reference image: the boundary's outline filled.
cv::Mat1b OutlineMask(const Boundary& boundary, int width, int height);

// Projection of M into the reference view; which triangles face the camera
// (paper is seen from its printed side: the orientation of the majority of
// the projected area) and the reference image's pixel density on M': the
// median over faces inside the image of sqrt(image area / M' area).
ProjectedMesh ProjectMesh(const RenderInputs& in);

// Box of the part of M' the reference view sees (M's raster mapped to M').
Eigen::Vector4d VisibleBox(const RasterResult& raster, const std::vector<Triangle>& tris,
                           const std::vector<Eigen::Vector2d>& flat);

struct SizeChoice {
  double scale = 0;  // output pixels per unit of M'
  int width = 0, height = 0;
  std::string rule;
  bool capped = false;
};

// The output size for a crop of crop_w x crop_h units of M' (`density`: the
// reference image's pixels per unit); UsageError when a requested size
// exceeds max_pixels.
SizeChoice ChooseSize(const RenderOptions& o, double crop_w, double crop_h, double density);

// The texture mapping proper: every output pixel's point of M' -> M ->
// reference pixel, sampled with the footprint of the pixel.
struct SampleStats {
  long page = 0, hidden = 0, minified = 0;
};

// The photos the texture is sampled from, each with the page's colour
// continued past its outline (options.page_edge).
struct TexturePhotos {
  cv::Mat reference;           // in.reference's
  std::vector<cv::Mat> views;  // in.views' (empty where a view has none)
};

// TexturePhotos of in.reference and, when `views_needed` (texture fusion,
// the page past cut sides), of in.views' photos, read once.
TexturePhotos ReadTexturePhotos(const RenderOptions& options, const RenderInputs& in,
                                bool views_needed);

// Samples every output pixel of `out_raster` (M' turned as `flat`, `scale`
// output pixels per unit) from `reference` (in.reference as textured) into
// *image, and its state (kOutside ... kHiddenSampled) into *state.
SampleStats SamplePixels(const RenderOptions& options, const RenderInputs& in,
                         const cv::Mat& reference, const ProjectedMesh& pm,
                         const std::vector<Eigen::Vector2d>& flat, const RasterResult& out_raster,
                         const RasterResult& ref_raster, double scale, cv::Mat3b* image,
                         cv::Mat1b* state);

// The texture from every photo (options.texture == kFusion,
// common/texture_fusion.h) over the same output pixels as SamplePixels
// (`out_pixel`: M's vertices there, as `out_raster` was rasterized),
// with the same states: kPage where some photo sees M, kHidden where none
// does (with --sample-hidden, the reference photo's colour there,
// kHiddenSampled). r->texture_labels and r->texture_views; r->timings gets
// the fusion's steps.
SampleStats FusePixels(const RenderOptions& options, const RenderInputs& in,
                       const ProjectedMesh& pm, const std::vector<Eigen::Vector2d>& flat,
                       const std::vector<Eigen::Vector2d>& out_pixel,
                       const RasterResult& out_raster, const RasterResult& ref_raster, double scale,
                       const TexturePhotos& photos, cv::Mat3b* image, cv::Mat1b* state,
                       RenderResult* r);

// Per-channel median colour of the page pixels (the paper, on a document).
cv::Vec3b MedianColour(const cv::Mat3b& image, const cv::Mat1b& state);

// The edges of M' over the image: every k-th grid line (k keeps drawn lines
// at least `min_spacing` pixels apart) and always the border rows/columns;
// points of M' that the reference view does not see are tinted.
cv::Mat3b DrawGrid(const cv::Mat3b& image, const cv::Mat1b& state, const MeshPair& m,
                   const std::vector<Eigen::Vector2d>& flat, const PixelFrame& frame,
                   const cv::Scalar& colour, double min_spacing, int* step);

// The boundary's sides mapped onto M' and their lines fitted (r->sides);
// returns each side's samples on M' (before the deskew turn).
std::array<std::vector<Eigen::Vector2d>, 4> FitSides(const RenderOptions& options,
                                                     const RenderInputs& in,
                                                     const PixelToSurface& lookup, RenderResult* r);

// The deskew turn of M' (radians; 0 when off or too large), taken from the
// page's lines or the fitted sides; sets r->deskew_source.
double DeskewAngle(const RenderOptions& options, const RenderInputs& in, RenderResult* r);

// What the crop step hands the rendering.
struct CropStep {
  std::vector<Eigen::Vector2d> flat;  // M' turned by the deskew angle
  CropRect crop;                      // before it is fitted to whole pixels
  // The reference's own outline as a view, when a real side was reached
  // past M's border (its strip is textured from the reference photo).
  std::vector<ViewMask> self_view;
};

// The crop of M' turned by `angle`: the sides' lines (r->sides, turned
// too), the page edge past cut sides (r->cut_edges), real sides reached past
// M's border (r->reached_sides), scattered sides' medians and the page
// format (r->page_format).
CropStep CropPage(const RenderOptions& options, const RenderInputs& in, const ProjectedMesh& pm,
                  double angle, const std::array<std::vector<Eigen::Vector2d>, 4>& side_points,
                  RenderResult* r);

}  // namespace docunfold::render
