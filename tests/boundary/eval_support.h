// What the boundary and feature tests share: every data set with ground
// truth, the views to check in each, and crops that cut the page off. The
// figures themselves are evaluate's (stages/evaluate/front_end.h).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

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

}  // namespace docunfold::testing
