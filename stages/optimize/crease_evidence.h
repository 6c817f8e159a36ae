// Where the reference photo shows a crease: a step in the paper's shading
// (its brightness with the print closed away) that is sharp at a fine scale
// and absent at a coarse one. A smooth curl shades the page gradually and
// gives nothing; a fold between two flat panels gives a line.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"

namespace docunfold::optimize {

struct CreaseOptions {
  // The photo is read at most this many pixels on its longer side; the
  // pixel sizes below are of that image.
  int max_side_px = 1600;
  // Print narrower than this (pixels) is closed away before the shading is
  // read.
  int ink_close_px = 15;
  // The fine and the coarse Gaussian scale of the step (pixels).
  double fine_sigma_px = 2;
  double coarse_sigma_px = 8;
  // Pixels this close to the page outline give no evidence (the outline is
  // the strongest step of all).
  double outline_margin_px = 12;
  // A triplet's E_fair(M) weight is 1 / (1 + (s / step)²), s the largest
  // step in log-brightness per pixel across it (0 = off). Measured: 0.0025
  // beats 0.00125, 0.002, 0.005 and 0.01 on the bench (docs/decisions/
  // optimize.md, "E_fair(M) spared where the photo shows a crease").
  double step = 0.0025;
  // and never below this.
  double min_weight = 0.02;
};

// The step across every direction, as the fine-minus-coarse gradient of
// log-brightness per pixel of `step` (two channels, x and y), zero outside
// the page; `step`'s pixel (u, v) is the photo's (u, v) / scale.
struct CreaseMap {
  cv::Mat2f step;
  double scale = 1;
};
CreaseMap CreaseEvidence(const cv::Mat& reference_bgr, const cv::Mat1b& page,
                         const CreaseOptions& options);

// λ3's weight per fair triplet (isometry::FairTriplets order) of M: where
// the triplet's projection into the reference crosses a shading step, E_fair
// bends there freely.
std::vector<double> CreaseFairWeights(const MeshPair& meshes, const PinholeCamera& reference,
                                      const CreaseMap& evidence, const CreaseOptions& options,
                                      int* spared = nullptr);

}  // namespace docunfold::optimize
