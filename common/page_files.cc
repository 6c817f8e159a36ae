#include "common/page_files.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/json_io.h"

namespace docunfold {

int Boundary::RealSides() const {
  int n = 0;
  for (const BoundarySide& s : sides) n += s.real;
  return n;
}

Boundary ReadBoundary(const fs::path& file) { return ParseBoundary(ReadJsonFile(file), file); }

Boundary ParseBoundary(const Json& doc, const fs::path& file) {
  CheckFormat(doc, file, "docunfold.boundary", 1);
  JsonReader r(doc, file);
  Boundary b;
  b.file = file;
  b.width = r.Integer("/width");
  b.height = r.Integer("/height");
  if (b.width <= 0 || b.height <= 0) r.Fail("/width", "image size must be positive");
  b.contour = r.Points("/contour", 3);
  const Json& corners = r.At("/corners");
  if (!corners.is_array() || corners.size() != 4) r.Fail("/corners", "expected 4 points");
  for (int i = 0; i < 4; ++i) b.corners[i] = r.Vector2("/corners/" + std::to_string(i));
  for (int i = 0; i < 4; ++i) {
    const std::string p = std::string("/sides/") + kSideNames[i];
    const Json& real = r.At(p + "/real");
    if (!real.is_boolean()) r.Fail(p + "/real", "expected true or false");
    b.sides[i].real = real.get<bool>();
    b.sides[i].points = r.Points(p + "/points", 2);
    if (b.sides[i].real) {
      b.sides[i].real_parts = {b.sides[i].points};
    } else if (r.Has(p + "/real_parts")) {
      const Json& parts = r.At(p + "/real_parts");
      if (!parts.is_array()) r.Fail(p + "/real_parts", "expected an array of polylines");
      for (size_t k = 0; k < parts.size(); ++k)
        b.sides[i].real_parts.push_back(r.Points(p + "/real_parts/" + std::to_string(k), 2));
    }
  }
  if (r.Has("/folded_corners")) {
    const Json& folded = r.At("/folded_corners");
    if (!folded.is_array()) r.Fail("/folded_corners", "expected an array");
    constexpr const char* kCornerNames[4] = {"TL", "TR", "BR", "BL"};
    for (size_t k = 0; k < folded.size(); ++k) {
      const std::string p = "/folded_corners/" + std::to_string(k);
      const std::string name = r.String(p + "/corner");
      const auto* it = std::find(std::begin(kCornerNames), std::end(kCornerNames), name);
      if (it == std::end(kCornerNames)) r.Fail(p + "/corner", "expected TL, TR, BR or BL");
      const std::vector<Eigen::Vector2d> fold = r.Points(p + "/fold", 2);
      b.folded_away.push_back({b.corners[it - std::begin(kCornerNames)], fold[0], fold[1]});
    }
  }
  return b;
}

FeatureFile ReadFeatures(const fs::path& file) {
  const Json doc = ReadJsonFile(file);
  CheckFormat(doc, file, "docunfold.features", 1);
  JsonReader r(doc, file);
  FeatureFile f;
  f.file = file;
  if (doc.contains("producer") && doc["producer"].is_object())
    f.producer = doc["producer"].value("stage", doc["producer"].value("program", ""));
  if (r.Has("/width")) f.width = r.Integer("/width");
  if (r.Has("/height")) f.height = r.Integer("/height");
  if (r.Has("/text_down")) {
    const Eigen::Vector2d d = r.Vector2("/text_down");
    if (!(d.norm() > 0.5 && d.norm() < 2)) r.Fail("/text_down", "expected a unit vector");
    f.text_down = d.normalized();
  }
  const Json& segments = r.At("/segments");
  if (!segments.is_array()) r.Fail("/segments", "expected an array");
  for (size_t i = 0; i < segments.size(); ++i) {
    const std::string p = "/segments/" + std::to_string(i);
    FeatureSegment s;
    s.kind = r.String(p + "/kind");
    if (s.kind != "text" && s.kind != "edge")
      r.Fail(p + "/kind", "expected \"text\" or \"edge\", found \"" + s.kind + "\"");
    s.points = r.Points(p + "/points", 2);
    f.segments.push_back(std::move(s));
  }
  return f;
}

cv::Mat1b ReadDocumentMask(const fs::path& path, int width, int height) {
  const cv::Mat mask = ReadImage(path, cv::IMREAD_GRAYSCALE);
  if (mask.cols != width || mask.rows != height)
    throw InputError(path.string() + ": " + std::to_string(mask.cols) + "x" +
                     std::to_string(mask.rows) + " differs from the reference image's " +
                     std::to_string(width) + "x" + std::to_string(height));
  cv::Mat1b region = mask > 0;
  if (cv::countNonZero(region) == 0)
    throw InputError(path.string() + ": empty document region (all pixels zero)");
  return region;
}

std::vector<ViewPage> ReadOtherViewPages(const CameraSet& cameras, const fs::path& cameras_file,
                                         const fs::path& boundary_dir) {
  const Json doc = ReadJsonFile(cameras_file);
  const JsonReader reader(doc, cameras_file);
  std::vector<ViewPage> pages;
  for (size_t i = 0; i < cameras.views.size(); ++i) {
    const PinholeCamera& view = cameras.views[i];
    if (view.image == cameras.reference) continue;
    const fs::path file = boundary_dir / "views" / fs::path(view.image).stem() / "mask.png";
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) continue;
    pages.push_back({view, ReadDistortion(reader, "/views/" + std::to_string(i)),
                     ReadDocumentMask(file, view.width, view.height), file});
  }
  return pages;
}

cv::Mat1b GrowRegion(const cv::Mat1b& region, double margin_px) {
  cv::Mat1b grown = region > 0;
  if (margin_px > 0) {
    const int r = int(std::ceil(margin_px));
    cv::dilate(grown, grown,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1)));
  }
  return grown;
}

cv::Mat1b ContourRegion(const Boundary& boundary, double margin_px) {
  cv::Mat1b region(boundary.height, boundary.width, uchar(0));
  std::vector<cv::Point> polygon;
  for (const Eigen::Vector2d& p : boundary.contour)
    polygon.emplace_back(int(std::lround(p.x())), int(std::lround(p.y())));
  if (polygon.size() >= 3) cv::fillPoly(region, std::vector<std::vector<cv::Point>>{polygon}, 255);
  return GrowRegion(region, margin_px);
}

std::vector<int> PointsInRegion(const std::vector<Eigen::Vector3d>& points,
                                const PinholeCamera& camera, const cv::Mat1b& region) {
  std::vector<int> inside;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d xc = camera.CamFromWorld(points[i]);
    if (!(xc.z() > 0)) continue;
    const Eigen::Vector2d px = camera.ProjectCam(xc);
    const long u = std::lround(px.x()), v = std::lround(px.y());
    if (u < 0 || v < 0 || u >= region.cols || v >= region.rows || !region(int(v), int(u))) continue;
    inside.push_back(int(i));
  }
  return inside;
}

}  // namespace docunfold
