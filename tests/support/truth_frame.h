// Ground truth expressed the way the pipeline sees a scene: in the frame of a
// reference camera, scaled so that the median depth of the page is 1 (the
// frame sfm writes, stages/sfm/sfm.h). Lets tests of later stages run on true inputs (cameras,
// points, meshes) without running sfm, and compare results with the truth.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>

#include "common/camera.h"
#include "common/ply.h"
#include "tests/support/ground_truth.h"

namespace docunfold::testing {

// x_ref = scale * (R * x_world + t): the reference camera's frame, scaled.
struct RefFromWorld {
  double scale = 1;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d operator()(const Eigen::Vector3d& x) const { return scale * (R * x + t); }
};

// The frame of `reference` (an image name of gt.cameras) with the median
// depth of the page vertices it sees set to 1.
RefFromWorld ReferenceFrame(const GroundTruth& gt, const std::string& reference);

// Every true camera re-expressed in that frame (same K, same image size).
CameraSet CamerasInReferenceFrame(const GroundTruth& gt, const std::string& reference);

// The true surface as the pipeline's pair of meshes: M (`mesh3d`, in the
// reference frame) and M' (`mesh2d`, the flat page in z = 0 with x right and
// y down, same length unit). Both keep the ground truth's grid and faces.
struct TrueMeshes {
  PlyData mesh3d;
  PlyData mesh2d;
};
TrueMeshes TrueMeshesInReferenceFrame(const GroundTruth& gt, const std::string& reference);

struct SfmFromTruthOptions {
  int num_points = 3000;          // surface samples seen by >= 2 views
  double noise = 0.002;           // Gaussian noise, fraction of the page diagonal
  double outlier_fraction = 0.0;  // extra points uniform in the page's bounding box
  unsigned seed = 1;
};

// Writes what sfm would write for `reference` from the ground truth:
// cameras.json (docunfold.cameras), points.ply and reference.png (the photo,
// which has no lens distortion in synthetic sets).
void WriteSfmFromTruth(const GroundTruth& gt, const std::string& reference, const fs::path& out_dir,
                       const SfmFromTruthOptions& options = {});

}  // namespace docunfold::testing
