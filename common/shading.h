// Removing the light's shading from a flat page image: a fold's panels, a
// curl and the shadows across a photographed page leave the paper darker in
// some places than in others, which a scan does not have and which costs OCR
// most of its accuracy (the paper removes "the shadows caused by creases"
// before its OCR metrics). The paper's brightness is estimated everywhere
// and divided out, so that paper becomes one even colour and print keeps its
// contrast to it.
#pragma once

#include <opencv2/core.hpp>

namespace docunfold {

struct ShadingOptions {
  // Long side of the working copy on which the paper's brightness is
  // estimated (pixels); the estimate is smooth, so it is interpolated up.
  int work_size = 1000;
  // Radius of the grey-level closing that lifts print out of the estimate,
  // as a fraction of the working copy's long side: wider than a stroke of
  // text or a printed rule (0.008: 8 px at 1000).
  double stroke_fraction = 0.008;
  // Paper is what is as bright as the brightest paper within this fraction
  // of the long side, times min_paper_ratio, and of the paper's own
  // chromaticity (within max_chroma_distance: shading scales all channels
  // alike, coloured print does not). Elsewhere (a coloured banner, a black
  // block) the estimate is carried over from the paper around it.
  double envelope_fraction = 0.08;
  double min_paper_ratio = 0.4;
  double max_chroma_distance = 0.01;
  // The paper is mapped to this quantile of its estimated brightness (the
  // well-lit paper's colour), per channel.
  double white_quantile = 0.9;
};

struct ShadingRemoval {
  cv::Mat image;              // 8-bit BGR, the size of the input
  double paper_fraction = 0;  // of the working copy's pixels taken as paper
  cv::Vec3d paper_white;      // BGR the paper is mapped to
};

// `bgr`: 8-bit, 1 or 3 channels (a grey image is returned grey). An empty
// image or one without any paper is returned unchanged (paper_fraction 0).
ShadingRemoval RemoveShading(const cv::Mat& bgr, const ShadingOptions& options = {});

}  // namespace docunfold
