#include "common/camera.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "common/atomic_file.h"
#include "common/errors.h"

namespace docunfold {

const PinholeCamera* CameraSet::Find(const std::string& image) const {
  for (const PinholeCamera& c : views)
    if (c.image == image) return &c;
  return nullptr;
}

CameraSet ReadCameras(const fs::path& path) {
  Json doc = ReadJsonFile(path);
  JsonReader r(doc, path);
  std::string format = r.String("/format");
  if (format != "docunfold.gt-cameras" && format != "docunfold.cameras")
    r.Fail("/format",
           "expected \"docunfold.cameras\" or "
           "\"docunfold.gt-cameras\", found \"" +
               format + "\"");
  CheckFormat(doc, path, format, 1);
  CameraSet set;
  if (format == "docunfold.cameras") set.reference = r.String("/reference");
  const Json& views = r.At("/views");
  if (!views.is_array() || views.empty()) r.Fail("/views", "expected a non-empty array");
  for (size_t i = 0; i < views.size(); ++i) {
    std::string p = "/views/" + std::to_string(i);
    PinholeCamera c;
    c.image = r.String(p + "/image");
    c.width = r.Integer(p + "/width");
    c.height = r.Integer(p + "/height");
    if (c.width <= 0 || c.height <= 0) r.Fail(p + "/width", "must be positive");
    c.K = r.Matrix3(p + "/K");
    c.R = r.Matrix3(p + "/R");
    c.t = r.Vector3(p + "/t");
    if (!((c.R * c.R.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-4))
      r.Fail(p + "/R", "not a rotation matrix");
    if (!(c.K(0, 0) > 0 && c.K(1, 1) > 0)) r.Fail(p + "/K", "focal lengths must be positive");
    set.views.push_back(c);
  }
  if (!set.reference.empty() && !set.Find(set.reference))
    r.Fail("/reference", "names no view in /views");
  return set;
}

std::array<double, 4> ReadDistortion(const JsonReader& r, const std::string& view_pointer) {
  std::array<double, 4> d{};
  const std::string pointer = view_pointer + "/distortion";
  if (!r.Has(pointer)) return d;
  if (r.String(pointer + "/model") != "opencv")
    r.Fail(pointer + "/model", "only the \"opencv\" model (k1 k2 p1 p2) is understood");
  const Json& c = r.At(pointer + "/coefficients");
  if (!c.is_array() || c.size() != 4) r.Fail(pointer + "/coefficients", "expected 4 numbers");
  for (int i = 0; i < 4; ++i) d[i] = r.Number(pointer + "/coefficients/" + std::to_string(i));
  return d;
}

std::optional<Eigen::Vector2d> ProjectDistorted(const PinholeCamera& camera,
                                                const std::array<double, 4>& d,
                                                const Eigen::Vector3d& x_world) {
  const Eigen::Vector3d x = camera.CamFromWorld(x_world);
  if (!(x.z() > 0)) return std::nullopt;
  const double u = x.x() / x.z(), v = x.y() / x.z();
  const double r2 = u * u + v * v;
  const double radial = 1 + d[0] * r2 + d[1] * r2 * r2;
  const double ud = u * radial + 2 * d[2] * u * v + d[3] * (r2 + 2 * u * u);
  const double vd = v * radial + d[2] * (r2 + 2 * v * v) + 2 * d[3] * u * v;
  const Eigen::Vector3d p = camera.K * Eigen::Vector3d(ud, vd, 1);
  const Eigen::Vector2d pixel = p.head<2>() / p.z();
  if (!std::isfinite(pixel.x()) || !std::isfinite(pixel.y())) return std::nullopt;
  return pixel;
}

std::vector<Eigen::Vector2d> UndistortPixels(const Eigen::Matrix3d& K,
                                             const std::array<double, 4>& distortion,
                                             const std::vector<Eigen::Vector2d>& pixels) {
  if (pixels.empty()) return {};
  cv::Mat cv_K, dist(1, 4, CV_64F);
  cv::eigen2cv(K, cv_K);
  for (int i = 0; i < 4; ++i) dist.at<double>(0, i) = distortion[i];
  std::vector<cv::Point2d> in, out;
  for (const auto& p : pixels) in.emplace_back(p.x(), p.y());
  cv::undistortPoints(in, out, cv_K, dist, cv::noArray(), cv_K);
  std::vector<Eigen::Vector2d> result;
  for (const auto& p : out) result.emplace_back(p.x, p.y);
  return result;
}

cv::Mat ReadViewPhoto(const fs::path& path, const PinholeCamera& view, const fs::path& cameras_file,
                      PhotoColor color) {
  cv::Mat photo = ReadPhoto(path, color).image;
  if (photo.cols != view.width || photo.rows != view.height)
    throw InputError(path.string() + ": " + std::to_string(photo.cols) + "x" +
                     std::to_string(photo.rows) + " differs from its camera's " +
                     std::to_string(view.width) + "x" + std::to_string(view.height) + " in " +
                     cameras_file.string());
  return photo;
}

Json CameraToJson(const PinholeCamera& c) {
  return {{"image", c.image}, {"width", c.width}, {"height", c.height},
          {"K", ToJson(c.K)}, {"R", ToJson(c.R)}, {"t", ToJson(c.t)}};
}

}  // namespace docunfold
