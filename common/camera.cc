#include "common/camera.h"

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
    r.Fail("/format", "expected \"docunfold.cameras\" or "
                      "\"docunfold.gt-cameras\", found \"" + format + "\"");
  CheckFormat(doc, path, format, 1);
  CameraSet set;
  if (format == "docunfold.cameras") set.reference = r.String("/reference");
  const Json& views = r.At("/views");
  if (!views.is_array() || views.empty())
    r.Fail("/views", "expected a non-empty array");
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
    if (!(c.K(0, 0) > 0 && c.K(1, 1) > 0))
      r.Fail(p + "/K", "focal lengths must be positive");
    set.views.push_back(c);
  }
  if (!set.reference.empty() && !set.Find(set.reference))
    r.Fail("/reference", "names no view in /views");
  return set;
}

Json CameraToJson(const PinholeCamera& c) {
  return {{"image", c.image}, {"width", c.width}, {"height", c.height},
          {"K", ToJson(c.K)}, {"R", ToJson(c.R)}, {"t", ToJson(c.t)}};
}

}  // namespace docunfold
