// A sparse model in COLMAP's binary format (cameras.bin, images.bin,
// points3D.bin, as COLMAP 3.x writes them) and the camera models we use.
//
// COLMAP's conventions differ from ours (camera.h) in one place: its pixel
// coordinates put the centre of the top-left pixel at (0.5, 0.5), ours at
// (0, 0). PinholeK() converts. Distortion is applied to normalized
// coordinates x = K^-1 u exactly as OpenCV's radial model does, so
// OpenCvDistortion() can be used with our K and cv::undistort & co.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace docunfold::sfm {

namespace fs = std::filesystem;

// COLMAP's model ids (src/base/camera_models.h); the ones sfm may produce.
enum class ColmapCameraModel : int {
  kSimplePinhole = 0,  // f, cx, cy
  kPinhole = 1,        // fx, fy, cx, cy
  kSimpleRadial = 2,   // f, cx, cy, k
  kRadial = 3,         // f, cx, cy, k1, k2
};

// "SIMPLE_PINHOLE" etc.; throws std::invalid_argument for other ids.
std::string CameraModelName(int model_id);
// Model id of a name (case-sensitive, COLMAP's spelling); -1 if unknown.
int CameraModelId(const std::string& name);
// Number of parameters of a supported model; -1 if unsupported.
int CameraModelNumParams(int model_id);

struct ColmapCamera {
  uint32_t id = 0;
  int model_id = 0;
  int width = 0;
  int height = 0;
  std::vector<double> params;

  // Intrinsics in OUR pixel convention (centre of the top-left pixel at 0,0).
  Eigen::Matrix3d PinholeK() const;
  double MeanFocal() const;
  // OpenCV distCoeffs (k1, k2, p1, p2) on normalized coordinates; all zero
  // for the pinhole models.
  std::array<double, 4> OpenCvDistortion() const;
  bool HasDistortion() const;
  // Pixel (our convention) of a point in camera coordinates, z > 0.
  Eigen::Vector2d Project(const Eigen::Vector3d& x_cam) const;
};

struct ColmapImage {
  uint32_t id = 0;
  uint32_t camera_id = 0;
  std::string name;
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // cam_from_world
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  size_t num_points2d = 0;
  size_t num_points3d = 0;  // observations with a 3D point

  Eigen::Matrix3d R() const { return q.toRotationMatrix(); }
  Eigen::Vector3d Center() const { return -(R().transpose() * t); }
};

struct ColmapPoint {
  uint64_t id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  std::array<uint8_t, 3> rgb{};
  double error = 0;                 // mean reprojection error, pixels
  std::vector<uint32_t> image_ids;  // the track (one entry per observation)
};

struct ColmapModel {
  std::map<uint32_t, ColmapCamera> cameras;
  std::map<uint32_t, ColmapImage> images;  // registered images only
  std::vector<ColmapPoint> points;

  double MeanReprojectionError() const;
  size_t NumObservations() const;
};

// Reads <dir>/{cameras,images,points3D}.bin; throws std::runtime_error naming
// the file on truncated or inconsistent data.
ColmapModel ReadColmapModel(const fs::path& dir);

}  // namespace docunfold::sfm
