// Texture fusion in render: M and the output frame handed to
// common/texture_fusion.h with the reference photo and the other views'.
#include <opencv2/imgproc.hpp>

#include "stages/render/render_internal.h"

namespace docunfold::render {

TexturePhotos ReadTexturePhotos(const RenderOptions& options, const RenderInputs& in,
                                bool views_needed) {
  TexturePhotos photos;
  photos.reference =
      ContinuePageColour(in.reference, ContourRegion(in.boundary, 0), options.page_edge);
  photos.views.resize(in.views.size());
  if (!views_needed) return photos;
  for (size_t v = 0; v < in.views.size(); ++v) {
    const ViewMask& view = in.views[v];
    if (view.photo.empty()) continue;
    photos.views[v] = ContinuePageColour(ReadViewPhoto(view.photo, view.camera, in.cameras_file),
                                         view.mask, options.page_edge);
  }
  return photos;
}

SampleStats FusePixels(const RenderOptions& options, const RenderInputs& in,
                       const ProjectedMesh& pm, const std::vector<Eigen::Vector2d>& flat,
                       const std::vector<Eigen::Vector2d>& out_pixel,
                       const RasterResult& out_raster, const RasterResult& ref_raster, double scale,
                       const TexturePhotos& photos, cv::Mat3b* image, cv::Mat1b* state,
                       RenderResult* r) {
  const int W = out_raster.face.cols, H = out_raster.face.rows;
  FusionSurface surface;
  surface.world = in.meshes.mesh3d;
  surface.pixel = out_pixel;
  surface.triangles = pm.triangles;
  surface.width = W;
  surface.height = H;
  // The reference first: reference.png, undistorted; its outline is where
  // M comes from, so it needs no mask, but where a corner is folded away
  // past its outline.
  cv::Mat1b reference_mask;
  if (!in.boundary.folded_away.empty()) {
    reference_mask = cv::Mat1b(photos.reference.size(), uchar(255));
    for (const auto& triangle : in.boundary.folded_away) {
      std::vector<cv::Point> corners;
      for (const Eigen::Vector2d& p : triangle)
        corners.emplace_back(int(std::lround(p.x())), int(std::lround(p.y())));
      cv::fillConvexPoly(reference_mask, corners, cv::Scalar(0));
    }
  }
  std::vector<FusionView> views = {
      {in.camera, {}, photos.reference, reference_mask, in.camera.image}};
  for (size_t v = 0; v < in.views.size(); ++v)
    if (!photos.views[v].empty())
      views.push_back({in.views[v].camera, in.views[v].distortion, photos.views[v],
                       in.views[v].mask, in.views[v].camera.image});
  FusionOptions fusion = options.fusion;
  fusion.antialias = options.antialias;
  FusedTexture fused = FuseTexture(surface, views, fusion);
  r->texture_timings = fused.timings;

  *image = fused.image;
  *state = cv::Mat1b(H, W, kOutside);
  state->setTo(kPage, fused.seen);
  state->setTo(kHidden, fused.label == kFusionUnseen);
  SampleStats stats;
  stats.page = cv::countNonZero(fused.seen);
  stats.hidden = cv::countNonZero(fused.label == kFusionUnseen);
  stats.minified = cv::countNonZero(fused.minified);
  if (options.sample_hidden && stats.hidden > 0) {
    cv::Mat3b reference_image;
    cv::Mat1b reference_state;
    SamplePixels(options, in, photos.reference, pm, flat, out_raster, ref_raster, scale,
                 &reference_image, &reference_state);
    const cv::Mat1b sampled = (*state == kHidden) & (reference_state == kHiddenSampled);
    reference_image.copyTo(*image, sampled);
    state->setTo(kHiddenSampled, sampled);
  }
  r->texture_labels = fused.label;
  r->texture_views = fused.views;
  r->texture_unseen = fused.unseen;
  return stats;
}

}  // namespace docunfold::render
