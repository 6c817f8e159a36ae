// The steps of texture fusion (texture_fusion.cc) that bring the photos
// together before the labelling: levelling, registration and sharpness
// (texture_registration.cc).
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "common/texture_fusion.h"

namespace docunfold::fusion_internal {

// One photo's rendering of the whole surface in the output frame.
struct ViewRendering {
  cv::Mat3b colour;
  cv::Mat1f resolution;  // photo pixels per output pixel, worse direction; 0 = not seen
  cv::Mat1b minified;
  cv::Mat1b Valid() const { return resolution > 0; }
};

// Levels every view but the reference (renderings[0]) to it by smooth gain
// fields and registers it by optical flow, the ones that overlap most first:
// each joins the target where it is still empty, so that a view overlapping
// only another non-reference view is levelled through it. Gains and flow go
// into `reports`.
void LevelAndRegister(const FusionOptions& o, std::vector<ViewRendering>* renderings,
                      std::vector<FusionViewReport>* reports);

// Per view, how sharp it is against how finely it resolves the surface (1:
// as sharp as the sharpest; 0.3: blurred like a photo with a third of its
// resolution), from the squared gradients of the levelled renderings where
// two views resolve the surface about equally finely. A view shaken or out
// of focus is what this catches; differences within
// options.sharpness_tolerance count as 1.
std::vector<double> RelativeSharpness(const FusionOptions& o, const std::vector<ViewRendering>& r,
                                      long surface_pixels);

}  // namespace docunfold::fusion_internal
