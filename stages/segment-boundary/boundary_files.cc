// What segment-boundary writes: boundary.json, overlay.png and mask.png, for
// the reference image and for every other view.
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/atomic_file.h"
#include "common/camera.h"
#include "common/errors.h"
#include "common/program.h"
#include "stages/segment-boundary/segment_boundary.h"

namespace docunfold::boundary {

Json BoundaryToJson(const BoundaryResult& r, const std::string& image_name, int width, int height,
                    const Json& options_record) {
  auto pt = [](const cv::Point2d& p) { return Json::array({p.x, p.y}); };
  auto line = [&](const std::vector<cv::Point2d>& pts) {
    Json a = Json::array();
    for (const auto& p : pts) a.push_back(pt(p));
    return a;
  };
  Json doc = MakeHeader("docunfold.boundary", 1, "segment-boundary", options_record);
  doc["image"] = image_name;
  doc["width"] = width;
  doc["height"] = height;
  doc["area_fraction"] = r.area_fraction;
  doc["contour"] = line(r.contour);
  doc["corners"] = Json::array();
  doc["corner_names"] = Json::array();
  doc["corners_in_image"] = Json::array();
  for (int i = 0; i < 4; ++i) {
    doc["corners"].push_back(pt(r.corners[i]));
    doc["corner_names"].push_back(kCornerNames[i]);
    doc["corners_in_image"].push_back(bool(r.corner_in_image[i]));
  }
  doc["sides"] = Json::object();
  for (int i = 0; i < 4; ++i) {
    const Side& s = r.sides[i];
    Json parts = Json::array();
    for (const auto& p : s.real_parts) parts.push_back(line(p));
    doc["sides"][kSideNames[i]] = {{"points", line(s.points)},
                                   {"real", s.real},
                                   {"cut_fraction", s.cut_fraction},
                                   {"real_parts", parts}};
  }
  if (!r.folded_corners.empty()) {
    doc["folded_corners"] = Json::array();
    for (const FoldedCorner& f : r.folded_corners)
      doc["folded_corners"].push_back(
          {{"corner", kCornerNames[f.corner]}, {"fold", line({f.fold[0], f.fold[1]})}});
  }
  doc["orientation"] = {{"method", r.orientation.method},
                        {"confidence", r.orientation.confidence},
                        {"votes", r.orientation.votes}};
  return doc;
}

cv::Mat DrawBoundaryOverlay(const cv::Mat& image, const BoundaryResult& r, int max_size) {
  const double s = std::min(1.0, double(max_size) / std::max(image.cols, image.rows));
  cv::Mat out, mask;
  cv::resize(image, out, cv::Size(), s, s, cv::INTER_AREA);
  cv::resize(r.mask, mask, out.size(), 0, 0, cv::INTER_NEAREST);
  // Darken the background so the region itself is visible.
  cv::Mat dark = out * 0.45;
  dark.copyTo(out, 255 - mask);
  const int thick = std::max(2, int(std::lround(out.cols / 500.0)));
  auto scaled = [&](const cv::Point2d& p) {
    return cv::Point(int(std::lround((p.x + 0.5) * s - 0.5)),
                     int(std::lround((p.y + 0.5) * s - 0.5)));
  };
  const cv::Scalar kReal(60, 220, 60), kCut(40, 40, 230), kCorner(0, 200, 255);
  for (int i = 0; i < 4; ++i) {
    const Side& side = r.sides[i];
    // Cut (non-real) stretches dashed red under the real parts in green.
    for (size_t k = 1; k < side.points.size(); ++k) {
      const cv::Point a = scaled(side.points[k - 1]), b = scaled(side.points[k]);
      const double len = cv::norm(b - a);
      const int dashes = std::max(1, int(len / (4.0 * thick)));
      for (int j = 0; j < dashes; j += 2) {
        const cv::Point2d p = cv::Point2d(a) + (cv::Point2d(b - a)) * (double(j) / dashes);
        const cv::Point2d q = cv::Point2d(a) + (cv::Point2d(b - a)) * (double(j + 1) / dashes);
        cv::line(out, p, q, kCut, thick, cv::LINE_AA);
      }
    }
    for (const auto& part : side.real_parts)
      for (size_t k = 1; k < part.size(); ++k)
        cv::line(out, scaled(part[k - 1]), scaled(part[k]), kReal, thick, cv::LINE_AA);
    // Side name just inside the page, at the middle of the side.
    const auto& pts = side.points;
    const cv::Point2d mid = pts[pts.size() / 2];
    cv::Point2d centre(0, 0);
    for (const auto& c : r.corners) centre += c * 0.25;
    cv::Point2d dir = centre - mid;
    dir *= 1.0 / std::max(1e-9, cv::norm(dir));
    const std::string label = std::string(kSideNames[i]) + (side.real ? "" : " (cut)");
    const double font = 0.5 * thick;
    int base = 0;
    const cv::Size ts = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, font, thick, &base);
    const cv::Point at =
        scaled(mid) + cv::Point(dir * 14.0 * thick) - cv::Point(ts.width / 2, -ts.height / 2);
    cv::putText(out, label, at, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(0, 0, 0), thick + 2,
                cv::LINE_AA);
    cv::putText(out, label, at, cv::FONT_HERSHEY_SIMPLEX, font, side.real ? kReal : kCut, thick,
                cv::LINE_AA);
  }
  for (int i = 0; i < 4; ++i) {
    const cv::Point c = scaled(r.corners[i]);
    cv::circle(out, c, 3 * thick, kCorner, thick, cv::LINE_AA);
    cv::putText(out, kCornerNames[i], c + cv::Point(4 * thick, -4 * thick),
                cv::FONT_HERSHEY_SIMPLEX, 0.6 * thick, cv::Scalar(0, 0, 0), thick + 2, cv::LINE_AA);
    cv::putText(out, kCornerNames[i], c + cv::Point(4 * thick, -4 * thick),
                cv::FONT_HERSHEY_SIMPLEX, 0.6 * thick, kCorner, thick, cv::LINE_AA);
  }
  const std::string note = "orientation: " + r.orientation.method;
  cv::putText(out, note, cv::Point(10, 10 + 12 * thick), cv::FONT_HERSHEY_SIMPLEX, 0.5 * thick,
              cv::Scalar(255, 255, 255), thick, cv::LINE_AA);
  return out;
}

std::vector<BoundaryFiles> SegmentOtherViews(const OtherViews& views, const fs::path& out_dir,
                                             const BoundaryOptions& options,
                                             const Json& options_record, int* tried) {
  std::vector<BoundaryFiles> outputs;
  *tried = 0;
  const CameraSet cameras = ReadCameras(views.cameras_path);
  for (const PinholeCamera& view : cameras.views) {
    if (view.image == cameras.reference) continue;
    ++*tried;
    const fs::path photo = views.views_dir / view.image;
    const cv::Mat view_image = ReadViewPhoto(photo, view, views.cameras_path);
    BoundaryResult result;
    try {
      result = SegmentBoundary(view_image, options);
    } catch (const InputError& e) {
      Log(photo.string() + ": " + e.what() + "; view left out");
      continue;
    }
    outputs.push_back(
        {out_dir / "views" / fs::path(view.image).stem(), result.mask,
         DrawBoundaryOverlay(view_image, result, 800),
         BoundaryToJson(result, view.image, view_image.cols, view_image.rows, options_record)});
  }
  return outputs;
}

void WriteBoundaryFiles(const BoundaryFiles& reference, const std::vector<BoundaryFiles>& views) {
  // Fast PNG compression: the mask compresses well anyway, the overlay is
  // for a quick look.
  const std::vector<int> png_fast = {cv::IMWRITE_PNG_COMPRESSION, 1};
  auto write = [&](const BoundaryFiles& files) {
    EnsureDirectory(files.dir);
    WriteImageAtomic(files.dir / "mask.png", files.mask, png_fast);
    WriteImageAtomic(files.dir / "overlay.png", files.overlay, png_fast);
    WriteJsonAtomic(files.dir / "boundary.json", files.doc);
  };
  write(reference);
  // Views of an earlier run would no longer match this boundary.
  std::error_code ec;
  fs::remove_all(reference.dir / "views", ec);
  for (const BoundaryFiles& v : views) write(v);
}

}  // namespace docunfold::boundary
