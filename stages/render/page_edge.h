// The page's colour continued past its outline in a photo, for texturing.
// The pixels just inside a photo's page outline mix paper and table (lens
// blur, demosaicing, JPEG), and the texture sampler's footprint at the
// crop's edge reaches a little past the outline: sampled as they are, they
// give the rectified page a darkened or tinted rim. See
// docs/decisions/render.md, "The page's rim".
#pragma once

#include <opencv2/core.hpp>

namespace docunfold::render {

struct PageEdgeOptions {
  // Pixels up to this far inside the outline are taken as mixed with the
  // background and replaced (0: the photo as it is).
  int mixed_px = 3;
  // How far past the outline the page's colour is continued: the reach of
  // the sampler's footprint where the page is minified a few times.
  int reach_px = 16;
};

// `photo` (8-bit BGR) with the band from options.mixed_px inside to
// options.reach_px outside the page (`page_mask` non-zero, the photo's size)
// given the colour of the nearest clean page pixel, thin print taken out.
// The image's border is no outline: a page cut off there keeps its pixels.
// Returns `photo` itself when mixed_px is 0 or the mask is empty.
cv::Mat ContinuePageColour(const cv::Mat& photo, const cv::Mat1b& page_mask,
                           const PageEdgeOptions& options);

}  // namespace docunfold::render
