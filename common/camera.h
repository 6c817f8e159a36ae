// The pinhole camera (OpenCV axes: x right, y down, z forward; pixel centres
// at integer coordinates) and the cameras.json files that hold sets of them.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/json_io.h"
#include "common/photo.h"

namespace docunfold {

struct PinholeCamera {
  std::string image;  // file name of the photo (relative to images/)
  int width = 0;      // image size in pixels
  int height = 0;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();  // intrinsics
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // cam_from_world rotation
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      // cam_from_world translation

  Eigen::Vector3d CamFromWorld(const Eigen::Vector3d& x_world) const { return R * x_world + t; }
  // Camera centre in world coordinates.
  Eigen::Vector3d Center() const { return -R.transpose() * t; }
  // Pixel of a point given in camera coordinates (z must be > 0).
  Eigen::Vector2d ProjectCam(const Eigen::Vector3d& x_cam) const {
    Eigen::Vector3d p = K * x_cam;
    return p.head<2>() / p.z();
  }
  Eigen::Vector2d Project(const Eigen::Vector3d& x_world) const {
    return ProjectCam(CamFromWorld(x_world));
  }
  // d(pixel)/d(x_cam) of ProjectCam at a point in camera coordinates (z > 0).
  Eigen::Matrix<double, 2, 3> ProjectCamJacobian(const Eigen::Vector3d& x_cam) const {
    const Eigen::Vector3d h = K * x_cam;
    const double u = h.x() / h.z(), v = h.y() / h.z();
    Eigen::Matrix<double, 2, 3> d;
    d.row(0) = (K.row(0) - u * K.row(2)) / h.z();
    d.row(1) = (K.row(1) - v * K.row(2)) / h.z();
    return d;
  }
  // The viewing ray of a pixel in camera coordinates, K^-1 (x, y, 1): the
  // point of depth 1 on it.
  Eigen::Vector3d CamRay(const Eigen::Vector2d& pixel) const {
    return K.inverse() * Eigen::Vector3d(pixel.x(), pixel.y(), 1);
  }
  // Unit viewing direction of a pixel, in world coordinates.
  Eigen::Vector3d RayDirection(const Eigen::Vector2d& pixel) const {
    return (R.transpose() * CamRay(pixel)).normalized();
  }
  // The world point seen at `pixel` at camera depth `depth`.
  Eigen::Vector3d LiftAtDepth(const Eigen::Vector2d& pixel, double depth) const {
    const Eigen::Vector3d x_cam = depth * (K.inverse() * Eigen::Vector3d(pixel.x(), pixel.y(), 1));
    return R.transpose() * (x_cam - t);
  }
};

// A cameras.json file: either ground truth ("docunfold.gt-cameras") or the
// output of sfm ("docunfold.cameras", which also names the reference view).
struct CameraSet {
  std::string reference;  // image name of the reference view ("" if none)
  std::vector<PinholeCamera> views;

  const PinholeCamera* Find(const std::string& image) const;
};

// Reads either format; validates shapes and finiteness (throws InputError).
CameraSet ReadCameras(const fs::path& path);

// The lens distortion of a view's photo as sfm's cameras.json gives it
// ("distortion": {"model": "opencv", "coefficients": [k1, k2, p1, p2]} under
// `view_pointer`, e.g. "/views/2"); zeros when absent (an undistorted image,
// like reference.png). InputError for another model or a malformed entry.
std::array<double, 4> ReadDistortion(const JsonReader& r, const std::string& view_pointer);

// Pixel of a world point in a photo with OpenCV's distortion (k1 k2 p1 p2);
// nullopt behind the camera.
std::optional<Eigen::Vector2d> ProjectDistorted(const PinholeCamera& camera,
                                                const std::array<double, 4>& distortion,
                                                const Eigen::Vector3d& x_world);

// The undistorted pixels (in the same intrinsics K) of photo pixels taken
// with OpenCV's distortion (k1 k2 p1 p2): ProjectDistorted's inverse.
std::vector<Eigen::Vector2d> UndistortPixels(const Eigen::Matrix3d& K,
                                             const std::array<double, 4>& distortion,
                                             const std::vector<Eigen::Vector2d>& pixels);

// The photo `path` of `view`, read upright by the photo reader (photo.h);
// InputError naming the file when it is missing, unreadable, damaged or not
// the size its camera in `cameras_file` says.
cv::Mat ReadViewPhoto(const fs::path& path, const PinholeCamera& view, const fs::path& cameras_file,
                      PhotoColor color = PhotoColor::kBgr);

// JSON for one camera: {"image","width","height","K","R","t"}.
Json CameraToJson(const PinholeCamera& camera);

}  // namespace docunfold
