#include "stages/report/stage_outputs.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/errors.h"

namespace docunfold::report {

namespace fs = std::filesystem;

cv::Mat DrawFeatureLines(const cv::Mat& rectified, const Json& render, const Json& lines) {
  if (rectified.empty() || !render.is_object() || !lines.is_object() || !lines.contains("lines") ||
      !render.contains("crop"))
    return {};
  const std::string meshes = render.value("/inputs/meshes"_json_pointer, std::string());
  if (fs::path(meshes).filename() != "50_optimize") return {};
  const double angle = render.value("rotation_deg", 0.0) * CV_PI / 180;
  const double scale = render.value("pixels_per_unit", 0.0);
  const double x0 = render["crop"].value("x0", 0.0), y0 = render["crop"].value("y0", 0.0);
  // Checked before the conversion: a float too large for an int has none.
  const Json quarter_turns =
      render.value("/orientation/quarter_turns_clockwise"_json_pointer, Json(0));
  if (!quarter_turns.is_number_integer())
    throw InputError(
        "60_render/render.json:/orientation/quarter_turns_clockwise: expected an "
        "integer");
  const int turns = int(((quarter_turns.get<long long>() % 4) + 4) % 4);
  if (!(scale > 0)) return {};
  // Size before the quarter turns.
  const int w = turns % 2 ? rectified.rows : rectified.cols;
  const int h = turns % 2 ? rectified.cols : rectified.rows;
  const double c = std::cos(angle), sn = std::sin(angle);
  auto to_px = [&](const Json& p) {
    const double fx = p[0].get<double>(), fy = p[1].get<double>();
    const double u = (c * fx - sn * fy - x0) * scale - 0.5;
    const double v = (sn * fx + c * fy - y0) * scale - 0.5;
    switch (turns) {  // as cv::rotate turns the image clockwise
      case 1:
        return cv::Point2d(h - 1 - v, u);
      case 2:
        return cv::Point2d(w - 1 - u, h - 1 - v);
      case 3:
        return cv::Point2d(v, w - 1 - u);
      default:
        return cv::Point2d(u, v);
    }
  };
  cv::Mat out = rectified.clone();
  const int thick = std::max(1, int(std::lround(std::max(out.cols, out.rows) / 600.0)));
  const Json& all = lines["lines"];
  if (!all.is_array()) throw InputError("50_optimize/lines.json:/lines: expected an array");
  for (size_t i = 0; i < all.size(); ++i) {
    const Json& line = all[i];
    if (!line.contains("flat") || !line["flat"].is_array()) continue;
    const std::string kind = line.value("kind", "");
    const cv::Scalar colour = kind == "text"   ? cv::Scalar(40, 40, 230)
                              : kind == "edge" ? cv::Scalar(230, 160, 0)
                                               : cv::Scalar(40, 180, 40);
    std::vector<cv::Point> poly;
    for (size_t k = 0; k < line["flat"].size(); ++k) {
      const Json& p = line["flat"][k];
      if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
        throw InputError("50_optimize/lines.json:/lines/" + std::to_string(i) + "/flat/" +
                         std::to_string(k) + ": expected [x, y]");
      const cv::Point2d q = to_px(p);
      poly.emplace_back(int(std::lround(q.x * 16)), int(std::lround(q.y * 16)));
    }
    if (poly.size() >= 2)
      cv::polylines(out, std::vector<std::vector<cv::Point>>{poly}, false, colour, thick,
                    cv::LINE_AA, 4);
  }
  return out;
}

std::string LinesNote(const Json& lines) {
  if (!lines.is_object() || !lines.contains("lines")) return "";
  std::map<std::string, int> kinds;
  for (const Json& l : lines["lines"]) kinds[l.value("kind", "?")]++;
  std::string note = "Feature lines straightened in M':";
  for (const auto& [k, n] : kinds) note += " " + std::to_string(n) + " " + k;
  return note + " (50_optimize/lines.json).";
}

std::string PointsCounts(const Json& points) {
  if (!points.is_object() || !points.contains("points")) return "";
  // Checked before the conversion: a float too large for an int has none.
  auto count = [&points](const std::string& key) {
    const Json n = points["points"].value(key, Json(0));
    if (!n.is_number_integer())
      throw InputError("25_points/points.json:/points/" + key + ": expected an integer");
    return std::to_string(n.get<long long>());
  };
  return " " + count("sfm_in_region") + " sfm points on the page, " + count("texture") +
         " texture, " + count("outline") + " outline.";
}

}  // namespace docunfold::report
