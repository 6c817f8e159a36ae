#include "stages/report/stage_outputs.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <vector>

#include "common/errors.h"
#include "common/program.h"
#include "stages/report/html.h"

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
  const double scale_y = render.value("pixels_per_unit_y", scale);  // absent: square pixels
  const double x0 = render["crop"].value("x0", 0.0), y0 = render["crop"].value("y0", 0.0);
  // Checked before the conversion: a float too large for an int has none.
  const Json quarter_turns =
      render.value("/orientation/quarter_turns_clockwise"_json_pointer, Json(0));
  if (!quarter_turns.is_number_integer())
    throw InputError(
        "60_render/render.json:/orientation/quarter_turns_clockwise: expected an "
        "integer");
  const int turns = int(((quarter_turns.get<long long>() % 4) + 4) % 4);
  if (!(scale > 0 && scale_y > 0)) return {};
  // Size before the quarter turns.
  const int w = turns % 2 ? rectified.rows : rectified.cols;
  const int h = turns % 2 ? rectified.cols : rectified.rows;
  // The box the warp put the sides' lines on (render.json's schema).
  const Json box = render["crop"].value("warp_box", Json::array());
  const bool has_box = box.is_array() && box.size() == 4;
  const double wx0 = has_box ? box[0].get<double>() : 0, wy0 = has_box ? box[1].get<double>() : 0;
  const double wx1 = has_box ? box[2].get<double>() : 1, wy1 = has_box ? box[3].get<double>() : 1;
  // The sides' lines render warped the page onto (render.json's schema):
  // point and direction, or none.
  std::array<std::optional<std::array<double, 4>>, 4> warped;  // top right bottom left
  const char* names[4] = {"top", "right", "bottom", "left"};
  const Json sides = render.value("/sides"_json_pointer, Json::object());
  for (int i = 0; i < 4; ++i) {
    const Json side = sides.is_object() ? sides.value(names[i], Json()) : Json();
    if (has_box && side.is_object() && side.value("warped", false) && side.contains("point") &&
        side.contains("direction"))
      warped[i] = std::array<double, 4>{
          side["point"][0].get<double>(), side["point"][1].get<double>(),
          side["direction"][0].get<double>(), side["direction"][1].get<double>()};
  }
  auto across = [&](int i, double along, double otherwise) {
    if (!warped[i]) return otherwise;
    const auto& [px, py, dx, dy] = *warped[i];
    return i % 2 == 0 ? py + (along - px) * dy / dx : px + (along - py) * dx / dy;
  };
  const double c = std::cos(angle), sn = std::sin(angle);
  auto to_px = [&](const Json& p) {
    const double fx = p[0].get<double>(), fy = p[1].get<double>();
    const double tx = c * fx - sn * fy, ty = sn * fx + c * fy;
    const double left = across(3, ty, wx0), right = across(1, ty, wx1);
    const double top = across(0, tx, wy0), bottom = across(2, tx, wy1);
    const double wx = wx0 + (tx - left) / (right - left) * (wx1 - wx0);
    const double wy = wy0 + (ty - top) / (bottom - top) * (wy1 - wy0);
    const double u = (wx - x0) * scale - 0.5;
    const double v = (wy - y0) * scale_y - 0.5;
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
         " texture, " + count("outline") + " outline, " + count("steps") + " shading-step, " +
         count("swept") + " swept.";
}

std::string PdfWordsSvg(const cv::Mat& page_image, const Json& pdf, int width) {
  if (page_image.empty() || !pdf.is_object() || !pdf.contains("words") || !pdf["words"].is_array())
    return {};
  std::vector<unsigned char> jpeg;
  cv::Mat shown;
  const double scale = std::min(1.0, 2.0 * width / page_image.cols);
  cv::resize(page_image, shown, cv::Size(), scale, scale, cv::INTER_AREA);
  cv::imencode(".jpg", shown, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80});
  const std::string w = std::to_string(page_image.cols), h = std::to_string(page_image.rows);
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(width) +
                    "\" viewBox=\"0 0 " + w + " " + h + "\"><image width=\"" + w + "\" height=\"" +
                    h + "\" href=\"data:image/jpeg;base64," + Base64(jpeg) + "\"/>";
  for (const Json& word : pdf["words"]) {
    if (!word.is_array() || word.size() != 6 || !word[5].is_string()) continue;
    const double x = word[0].get<double>(), y = word[1].get<double>();
    const double bw = word[2].get<double>(), bh = word[3].get<double>();
    const char* colour = word[4].get<double>() < 0.6 ? "#d62728" : "#1f77b4";
    svg += "<rect x=\"" + Fixed(x, 0) + "\" y=\"" + Fixed(y, 0) + "\" width=\"" + Fixed(bw, 0) +
           "\" height=\"" + Fixed(bh, 0) + "\" fill=\"white\" fill-opacity=\"0.75\"/>" +
           "<text x=\"" + Fixed(x, 0) + "\" y=\"" + Fixed(y + 0.85 * bh, 1) + "\" font-size=\"" +
           Fixed(bh, 1) + "\" textLength=\"" + Fixed(bw, 0) +
           "\" lengthAdjust=\"spacingAndGlyphs\" fill=\"" + colour + "\">" +
           MarkupEscape(word[5].get<std::string>()) + "</text>";
  }
  return svg + "</svg>";
}

std::string PdfSummary(const Json& pdf) {
  if (!pdf.is_object() || pdf.value("format", "") != "docunfold.pdf") return {};
  const Json page = pdf.value("page", Json::object()), text = pdf.value("text", Json::object());
  std::string format = page.value("format", "none");
  if (format.rfind("receipt-", 0) == 0)
    format = format.substr(8) + " mm receipt roll";
  else
    std::transform(format.begin(), format.begin() + 1, format.begin(), ::toupper);
  const Json dpi = page.value("dpi", Json::array());
  return (format == "None" ? std::string("No standard paper format") : "Paper " + format) + ", " +
         Fixed(page.value("width_mm", 0.0), 1) + " × " + Fixed(page.value("height_mm", 0.0), 1) +
         " mm (" + MarkupEscape(page.value("rule", "")) + "), " +
         (dpi.size() == 2 ? Fixed(dpi[0].get<double>(), 0) : std::string("?")) + " dpi; " +
         std::to_string(text.value("words", 0)) + " words read (" +
         MarkupEscape(text.value("language", "")) + "), mean confidence " +
         Fixed(text.value("mean_confidence", 0.0), 2) + "; " +
         std::to_string(pdf.value("/files/pdf_bytes"_json_pointer, 0) / 1024) + " KB.";
}

std::string PdfCheckSummary(const Json& metrics) {
  if (!metrics.is_object() || metrics.value("format", "") != "docunfold.pdf-metrics") return {};
  const Json text = metrics.value("text", Json::object()),
             page = metrics.value("page", Json::object());
  std::string s = "Read back against the true text: a search finds " +
                  Fixed(100 * text.value("words_found", 0.0), 1) + " % of its words";
  if (text.value("cer_reading_order", Json()).is_number())
    s += ", and copied text has a CER of " + Fixed(text["cer_reading_order"].get<double>(), 3);
  if (page.value("true_width_mm", Json()).is_number())
    s += "; the page is " + Fixed(page.value("width_mm", 0.0), 0) + " × " +
         Fixed(page.value("height_mm", 0.0), 0) + " mm, the true page " +
         Fixed(page["true_width_mm"].get<double>(), 0) + " × " +
         Fixed(page.value("true_height_mm", 0.0), 0) + " mm";
  return s + ".";
}

}  // namespace docunfold::report
