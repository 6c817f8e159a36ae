// What the boundary and feature tests share: every data set with ground
// truth, the views to check in each, crops that cut the page off, and the
// true page outline in a view.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "common/camera.h"
#include "tests/support/ground_truth.h"

namespace docunfold::testing {

// samples/* and ../shared/realistic/* that have ground_truth/cameras.json.
std::vector<fs::path> DataSetsWithTruth();
// "realistic/r01" or "samples/set03": a readable name for test output.
std::string DataSetName(const fs::path& dataset);

// Index (into gt.cameras.views) of the view that looks most squarely at the
// page among those that see all four corners (what sfm is likely to pick).
int MostFrontalView(const GroundTruth& gt);

// The photo of a view, and a crop of it with a camera to match (the same
// pinhole camera with its principal point shifted and a smaller image).
cv::Mat ReadView(const GroundTruth& gt, const PinholeCamera& camera);
PinholeCamera CropCamera(const PinholeCamera& camera, const cv::Rect& crop);

// The page's outline (the border of flat.png carried by the true surface)
// projected into `camera`, about every `step_px` flat pixels; points outside
// the image or hidden by the page are left out, so it may be in pieces.
std::vector<std::vector<Eigen::Vector2d>> TrueOutlineInView(const GroundTruth& gt,
                                                            const PinholeCamera& camera,
                                                            double step_px = 2.0);

// How a view shows each true corner (TrueCorners order): outside the image
// (or within `margin_px` of its border), visible, or hidden by the page
// itself (a flap folded over it).
enum class CornerView { kOutside, kVisible, kHidden };
std::array<CornerView, 4> TrueCornersInView(const GroundTruth& gt, const PinholeCamera& camera,
                                            double margin_px = 3.0);

// Mean length of the two diagonals of the true corners in the view.
double ProjectedDiagonal(const GroundTruth& gt, const PinholeCamera& camera);

// Distance from `p` to the nearest segment of any of `lines`.
double DistanceToPolylines(const Eigen::Vector2d& p,
                           const std::vector<std::vector<Eigen::Vector2d>>& lines);

double IntersectionOverUnion(const cv::Mat1b& a, const cv::Mat1b& b);

}  // namespace docunfold::testing
