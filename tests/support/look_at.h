// Cameras placed by where they stand and what they look at, for scenes
// made in tests.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "common/camera.h"

namespace docunfold::testing {

// cam_from_world of a camera at `centre` looking at `target` (OpenCV axes:
// z forward, the image's y as near world +y as the view allows).
inline Eigen::Matrix3d LookAtRotation(const Eigen::Vector3d& centre,
                                      const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - centre).normalized();
  Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z);
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d r;
  r.row(0) = x.transpose();
  r.row(1) = y.transpose();
  r.row(2) = z.transpose();
  return r;
}

// A `width` x `height` pinhole camera (focal `f` px, principal point at the
// image's centre) at `centre`, looking at `target`.
inline PinholeCamera LookAtCamera(const std::string& image, const Eigen::Vector3d& centre,
                                  const Eigen::Vector3d& target, int width, int height, double f) {
  PinholeCamera cam;
  cam.image = image;
  cam.width = width;
  cam.height = height;
  cam.K << f, 0, (width - 1) / 2.0, 0, f, (height - 1) / 2.0, 0, 0, 1;
  cam.R = LookAtRotation(centre, target);
  cam.t = -cam.R * centre;
  return cam;
}

}  // namespace docunfold::testing
