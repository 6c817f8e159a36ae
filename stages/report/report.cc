#include "stages/report/report.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "common/camera.h"
#include "common/dataset.h"
#include "common/errors.h"
#include "common/grid_mesh.h"
#include "common/json_io.h"
#include "common/option_table.h"
#include "common/photo.h"
#include "common/ply.h"
#include "common/program.h"
#include "common/texture_fusion.h"
#include "stages/report/html.h"
#include "stages/report/mesh_views.h"
#include "stages/report/stage_outputs.h"

namespace docunfold::report {
namespace {

// `v` by a printf format other than fixed-point ("%.3g", "%+.0f", ...);
// fixed-point numbers go through Fixed (common/cli.h).
std::string Fmt(double v, const char* format) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string ReadText(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A JSON file if it exists and parses; null otherwise (the report shows what
// there is and never fails on one stage's output).
Json TryJson(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return nullptr;
  try {
    return ReadJsonFile(p);
  } catch (const std::exception& e) {
    Log("warning: " + std::string(e.what()));
    return nullptr;
  }
}

cv::Mat TryImage(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return {};
  return cv::imread(p.string(), cv::IMREAD_COLOR);
}

std::string Missing(const std::string& what) {
  return "<p class=\"missing\">" + MarkupEscape(what) + "</p>";
}

class Page {
 public:
  void Section(const std::string& id, const std::string& title) {
    body_ += "<section id=\"" + id + "\"><h2>" + MarkupEscape(title) + "</h2>\n";
    toc_ += "<a href=\"#" + id + "\">" + MarkupEscape(title) + "</a> ";
  }
  void End() { body_ += "</section>\n"; }
  void Add(const std::string& html) { body_ += html; }
  std::string Html(const std::string& title, const std::string& summary) const {
    return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
           "<title>" +
           MarkupEscape(title) +
           "</title><style>"
           "body{font-family:sans-serif;margin:1.5em auto;max-width:1200px;color:#222}"
           "h1{margin-bottom:0.2em}h2{border-bottom:1px solid #ccc;padding-bottom:0.2em;"
           "margin-top:1.6em}nav a{margin-right:1em}figure{display:inline-block;margin:0.4em;"
           "vertical-align:top}figcaption{font-size:0.85em;color:#555;max-width:600px}"
           "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;"
           "padding:3px 8px;text-align:right}th{background:#f0f0f0}td.l,th.l{text-align:left}"
           ".ref{outline:4px solid #d62728}.missing{color:#a00;font-style:italic}"
           ".warning{color:#a00;font-weight:bold}"
           "code{background:#f4f4f4;padding:1px 3px}img{max-width:100%;height:auto}"
           "</style></head><body>\n<h1>" +
           MarkupEscape(title) + "</h1><p>" + summary + "</p><nav>" + toc_ + "</nav>\n" + body_ +
           "</body></html>\n";
  }

 private:
  std::string body_, toc_;
};

std::string Figure(const std::string& img, const std::string& caption) {
  return "<figure>" + img + "<figcaption>" + caption + "</figcaption></figure>";
}

// The newest entry per stage of <work>/timings.jsonl (pipeline.mk appends
// one line per stage run).
std::map<std::string, Json> StageTimings(const fs::path& work) {
  std::map<std::string, Json> out;
  std::ifstream f(work / "timings.jsonl");
  std::string line;
  while (std::getline(f, line)) {
    try {
      Json j = Json::parse(line);
      out[j.at("stage").get<std::string>()] = j;
    } catch (const std::exception&) {
    }
  }
  return out;
}

// True when the array at `pointer` in `doc` holds `name`, as a string or as
// an object's "image".
bool Lists(const Json& doc, const char* pointer, const std::string& name) {
  const Json::json_pointer at(pointer);
  if (!doc.is_object() || !doc.contains(at) || !doc[at].is_array()) return false;
  for (const Json& e : doc[at])
    if ((e.is_string() && e.get<std::string>() == name) ||
        (e.is_object() && e.value("image", "") == name))
      return true;
  return false;
}

void PhotosSection(const ReportOptions& o, const DataSet& data, const Json& cameras, Page* page) {
  page->Section("photos", "Photos and the reference view");
  std::string reference = cameras.is_object() ? cameras.value("reference", "") : "";
  std::string html;
  size_t photos = 0;
  for (const fs::path& p : data.images) {
    const std::string name = p.filename().string();
    // (a second file of a photo: listed below with what sfm left out)
    if (Lists(cameras, "/left_out", name)) continue;
    cv::Mat image;
    try {
      image = ReadPhoto(p).image;
    } catch (const InputError&) {
      continue;  // left out: listed below from cameras.json
    }
    ++photos;
    const bool is_ref = name == reference;
    std::string img = InlineImage(image, o.thumbnail_width, name);
    if (is_ref) img.insert(4, " class=\"ref\"");
    const bool registered = Lists(cameras, "/views", name);
    const bool apart = Lists(cameras, "/colmap/not_mapped", name);
    html += Figure(img, MarkupEscape(name) + (is_ref ? " — <b>reference</b>" : "") +
                            (cameras.is_object() && !registered
                                 ? apart ? " — not registered (no features in common with the "
                                           "registered ones: another page?)"
                                         : " — not registered"
                                 : ""));
  }
  page->Add(html);
  if (!cameras.is_object()) {
    page->Add(Missing("sfm has not run yet (10_sfm/cameras.json is missing)."));
  } else {
    std::string why =
        "Chosen automatically by sfm: the registered view that sees the whole "
        "page and resolves its worst-seen tenth best (resolution = pixels per "
        "unit of page length across the foreshortening).";
    const std::string flags = ReadText(o.work / ".flags/sfm");
    if (flags.find("--ref") != std::string::npos) why = "Chosen by the user (<code>REF=</code>).";
    // sfm's scores of every view (cameras.json /reference_selection/views).
    if (cameras.contains("reference_selection")) {
      const Json& c = cameras["reference_selection"];
      if (c.contains("views") && c["views"].is_array() && !c["views"].empty()) {
        why += "<table><tr><th class=l>view</th>";
        std::vector<std::string> keys;
        for (const auto& [k, v] : c["views"][0].items())
          if (k != "image" && v.is_number()) keys.push_back(k);
        for (const auto& k : keys) why += "<th>" + MarkupEscape(k) + "</th>";
        why += "</tr>";
        for (const Json& cand : c["views"]) {
          why += "<tr><td class=l>" + MarkupEscape(cand.value("image", "?")) + "</td>";
          for (const auto& k : keys)
            why += "<td>" +
                   (cand.contains(k) && cand[k].is_number() ? Fmt(cand[k].get<double>(), "%.3g")
                                                            : std::string("–")) +
                   "</td>";
          why += "</tr>";
        }
        why += "</table>";
      }
    }
    const Json left_out_files = cameras.contains("left_out") && cameras["left_out"].is_array()
                                    ? cameras["left_out"]
                                    : Json::array();
    std::string left_out;
    for (const Json& l : left_out_files)
      left_out += "<li>" + MarkupEscape(l.value("image", "?")) + " (" +
                  MarkupEscape(l.value("reason", "")) + ")</li>";
    page->Add("<p>" + std::to_string(cameras.at("views").size()) + " of " + std::to_string(photos) +
              " photos registered. " + why + "</p>" +
              (left_out.empty() ? "" : "<p>Left out:</p><ul>" + left_out + "</ul>"));
  }
  page->End();
}

void BoundarySection(const ReportOptions& o, Page* page) {
  page->Section("boundary", "Boundary and feature segments");
  const Json boundary = TryJson(o.work / "20_boundary/boundary.json");
  const cv::Mat overlay = TryImage(o.work / "20_boundary/overlay.png");
  if (!overlay.empty()) {
    std::string caption = "Document boundary (20_boundary/overlay.png).";
    if (boundary.is_object() && boundary.contains("sides")) {
      caption += " Sides:";
      for (const char* s : {"top", "right", "bottom", "left"})
        if (boundary["sides"].contains(s))
          caption += std::string(" ") + s + " " +
                     (boundary["sides"][s].value("real", false) ? "real" : "<b>cut off</b>");
    }
    page->Add(Figure(InlineImage(overlay, o.figure_width / 2 + 100, "boundary"), caption));
  } else {
    page->Add(Missing("segment-boundary has not run yet."));
  }
  const Json features = TryJson(o.work / "30_features/features.json");
  const cv::Mat foverlay = TryImage(o.work / "30_features/overlay.png");
  std::string caption;
  if (features.is_object() && features.contains("segments")) {
    int text = 0, edge = 0;
    for (const Json& s : features["segments"]) (s.value("kind", "") == "text" ? text : edge)++;
    caption = std::to_string(text) + " text and " + std::to_string(edge) +
              " edge segments (30_features/features.json).";
    if (features.contains("producer") &&
        features["producer"].value("stage", "") != "detect-features")
      caption += " From another detector.";
  }
  if (!foverlay.empty())
    page->Add(Figure(InlineImage(foverlay, o.figure_width / 2 + 100, "features"), caption));
  else if (!caption.empty())
    page->Add("<p>" + caption + " (no overlay: the file came from another detector)</p>");
  else
    page->Add(Missing("detect-features has not run yet."));
  page->End();
}

void MeshSection(const ReportOptions& o, const Json& cameras, Page* page, fs::path* mesh_dir) {
  page->Section("meshes", "Point cloud and meshes");
  *mesh_dir = fs::path();
  for (const char* d : {"50_optimize", "40_init"})
    if (fs::is_regular_file(o.work / d / "mesh3d.ply")) {
      *mesh_dir = o.work / d;
      break;
    }
  if (mesh_dir->empty() || !cameras.is_object()) {
    page->Add(Missing("No meshes yet (init-mesh has not run)."));
    page->End();
    return;
  }
  try {
    const MeshPair mesh = ReadMeshPair(*mesh_dir);
    const CameraSet set = ReadCameras(o.work / "10_sfm/cameras.json");
    const PinholeCamera* ref = set.Find(set.reference);
    std::vector<Eigen::Vector3d> points;
    std::error_code ec;
    for (const char* cloud : {"25_points/points.ply", "10_sfm/points.ply"})
      if (fs::is_regular_file(o.work / cloud, ec)) {
        points = ReadPly(o.work / cloud).vertices;
        break;
      }
    const cv::Mat texture = TryImage(o.work / "10_sfm/reference.png");
    std::string html;
    for (auto [yaw, pitch] : {std::pair<double, double>{-35, -20}, {40, 25}}) {
      MeshViewOptions v;
      v.yaw_deg = yaw;
      v.pitch_deg = pitch;
      cv::Mat picture = RenderMeshView(mesh, *ref, texture, points, v);
      html += Figure(InlineImage(picture, v.width, "M"),
                     "M from " + Fmt(yaw, "%+.0f") + "°, " + Fmt(pitch, "%+.0f") +
                         "° off the reference view, with the points (red)");
    }
    page->Add(html);
    const cv::Mat points_overlay = TryImage(o.work / "25_points/overlay.png");
    if (!points_overlay.empty()) {
      const Json counts = TryJson(o.work / "25_points/points.json");
      std::string caption =
          "The points fitted (25_points/overlay.png): sfm's (blue), and densify's texture "
          "(green), outline (magenta), shading-step (yellow) and swept (orange) points.";
      caption += PointsCounts(counts);
      page->Add(Figure(InlineImage(points_overlay, o.figure_width / 2 + 100, "points"), caption));
    }
    page->Add("<p>M and M' from <code>" + MarkupEscape(mesh_dir->filename().string()) +
              "/</code>: " + std::to_string(mesh.grid.nx) + " × " + std::to_string(mesh.grid.ny) +
              " vertices; " + std::to_string(points.size()) +
              " points. Open <code>mesh3d.ply</code> in MeshLab to see M textured, or "
              "<code>50_optimize/scene.glb</code> in any glTF viewer.</p>");
  } catch (const std::exception& e) {
    page->Add(Missing(std::string("Cannot draw the meshes: ") + e.what()));
  }
  page->End();
}

void ConvergenceSection(const ReportOptions& o, Page* page) {
  page->Section("convergence", "Convergence of the optimisation");
  const Json log = TryJson(o.work / "50_optimize/log.json");
  if (!log.is_object() || !log.contains("rounds")) {
    page->Add(Missing("optimize has not run yet (50_optimize/log.json is missing)."));
    page->End();
    return;
  }
  std::vector<PlotPoint> points;
  PlotOptions plot;
  plot.x_label = "time (s)";
  plot.y_label = "F";
  plot.log_y = true;
  std::string table =
      "<table><tr><th class=l>round</th><th>grid</th><th>iterations</th>"
      "<th>final F</th><th>seconds</th><th class=l>stopped</th></tr>";
  for (const Json& round : log["rounds"]) {
    const int r = round.value("round", 0);
    plot.series_names.push_back("round " + std::to_string(r));
    double last_f = 0, last_t = 0;
    for (const Json& it : round.value("iterations", Json::array())) {
      last_f = it.value("F", 0.0);
      last_t = it.value("seconds", 0.0);
      points.push_back({last_t, last_f, r});
    }
    std::string grid = "–";
    if (round.contains("grid") && round["grid"].size() == 2)
      grid = std::to_string(round["grid"][0].get<int>()) + "×" +
             std::to_string(round["grid"][1].get<int>());
    table += "<tr><td class=l>" + std::to_string(r) + "</td><td>" + grid + "</td><td>" +
             std::to_string(round.value("iterations", Json::array()).size()) + "</td><td>" +
             Fmt(last_f, "%.3e") + "</td><td>" + Fixed(last_t, 2) + "</td><td class=l>" +
             MarkupEscape(round.value("stop_reason", "")) + "</td></tr>";
  }
  table += "</table>";
  page->Add(SvgScatter(points, plot));
  page->Add(
      "<p>Each dot is one outer iteration (footpoints, outliers and feature lines "
      "recomputed, then one solver step); colours are rounds, separated by "
      "Catmull–Clark subdivision.</p>" +
      table);
  page->End();
}

std::string MetricsRow(const Json& m) {
  const Json& v = m.at("metrics");
  auto cell = [&](const char* key, int decimals) {
    return "<td>" +
           (v.contains(key) && v[key].is_number() ? Fixed(v[key].get<double>(), decimals)
                                                  : std::string("–")) +
           "</td>";
  };
  return "<tr><td class=l>" + MarkupEscape(m.value("method", "?")) + "</td>" + cell("ms_ssim", 4) +
         cell("ld", 2) + cell("li_d", 2) + cell("cer", 3) + cell("wer", 3) +
         cell("surface_mean_pct", 2) + cell("isometry_mean", 4) + "</tr>";
}

// What ✗ means after a figure of FrontEndParagraph, with the thresholds
// front_end.json holds.
std::string FrontEndLegend(const Json& thresholds) {
  auto value = [&](const char* key, double scale = 1) {
    return thresholds.contains(key) && thresholds[key].is_number()
               ? Fmt(scale * thresholds[key].get<double>(), "%g")
               : std::string("?");
  };
  return "✗ = short of its threshold (evaluate --front-end): boundary IoU with the true page "
         "region at least " +
         value("boundary_iou") + "; every visible true corner within " +
         value("corner_fraction_of_diagonal", 100) +
         " % of the page diagonal of a detected corner; a side flagged cut when the page is "
         "cut off in the photo, none when it is seen whole; feature precision: at least " +
         value("line_precision", 100) + " % of the segments' length within " +
         value("line_tolerance_px") +
         " px of a true line; recall (on text pages and tables): segments along at least " +
         value("line_recall", 100) + " % of the true lines' length.";
}

// evaluate --front-end's figures in one sentence, misses marked.
std::string FrontEndParagraph(const Json& f) {
  auto number = [](const Json& o, const char* key, int decimals, double scale = 1) {
    return o.contains(key) && o[key].is_number() ? Fixed(scale * o[key].get<double>(), decimals)
                                                 : std::string("–");
  };
  auto miss = [](const Json& o, const char* key) {
    return o.contains("holds") && !o["holds"].value(key, true) ? std::string(" ✗") : "";
  };
  std::string p =
      "<p>Front end against the ground truth in " + MarkupEscape(f.value("reference", "?")) + ": ";
  const Json& b = f.value("boundary", Json::object());
  if (b.contains("iou"))
    p += "boundary IoU " + number(b, "iou", 4) + miss(b, "iou") + ", worst visible corner " +
         number(b, "worst_corner_fraction", 2, 100) + " % of the page diagonal" +
         miss(b, "corners") + ", " + std::to_string(b.value("sides_not_real", 0)) +
         " side(s) flagged cut" + (b.value("page_cut", false) ? " (the page is cut)" : "") +
         miss(b, "cut_flags") + "; ";
  const Json& l = f.value("features", Json::object());
  if (l.contains("precision"))
    p += "feature segments: precision " + number(l, "precision", 3) + miss(l, "precision") +
         ", recall " + number(l, "recall", 3) + miss(l, "recall") +
         (l.value("recall_required", false) ? "" : " (not required on this kind of page)");
  return p + ". " + FrontEndLegend(f.value("thresholds", Json::object())) + "</p>";
}

void ResultSection(const ReportOptions& o, const DataSet& data, const fs::path& mesh_dir,
                   Page* page) {
  page->Section("result", "The rectified page");
  const cv::Mat rectified = TryImage(o.work / "60_render/rectified.png");
  const cv::Mat grid = TryImage(o.work / "60_render/rectified_grid.png");
  if (rectified.empty()) {
    page->Add(Missing("render has not run yet."));
    page->End();
    return;
  }
  std::string html = Figure(InlineImage(rectified, o.figure_width / 2, "rectified"),
                            "60_render/rectified.png (" + std::to_string(rectified.cols) + " × " +
                                std::to_string(rectified.rows) + ")");
  if (!grid.empty())
    html += Figure(
        InlineImage(grid, o.figure_width / 2, "rectified with M'"),
        "The same with the edges of M' (from " + MarkupEscape(mesh_dir.filename().string()) + ")");
  const cv::Mat labels = TryImage(o.work / "60_render/texture_labels.png");
  const Json render_json = TryJson(o.work / "60_render/render.json");
  if (render_json.is_object() && render_json.contains("warnings") &&
      render_json["warnings"].is_array())
    for (const Json& w : render_json["warnings"])
      if (w.is_string())
        page->Add("<p class=\"warning\">render: " + MarkupEscape(w.get<std::string>()) + "</p>");
  if (!labels.empty() && render_json.is_object() && render_json.contains("texture")) {
    std::string legend;
    const Json& views = render_json["texture"].value("views", Json::array());
    for (size_t v = 0; v < views.size(); ++v) {
      const cv::Vec3b c = LabelColour(int(v));
      char hex[8];
      std::snprintf(hex, sizeof hex, "#%02x%02x%02x", c[2], c[1], c[0]);
      legend += std::string(v == 0 ? "" : ", ") + "<span style=\"color:" + hex + "\">■</span> " +
                MarkupEscape(views[v].value("view", "?")) + (v == 0 ? " (reference) " : " ") +
                Fixed(100 * views[v].value("share", 0.0), 1) + " %";
    }
    html += Figure(
        InlineImage(labels, o.figure_width / 2, "texture labels"),
        "Which photo coloured each part of the page (60_render/texture_labels.png): " + legend +
            "; grey: no photo sees it (" +
            Fixed(100 * render_json["texture"].value("unseen_fraction", 0.0), 1) + " %, filled)");
  }
  const Json lines = TryJson(o.work / "50_optimize/lines.json");
  const cv::Mat with_lines = DrawFeatureLines(rectified, render_json, lines);
  if (!with_lines.empty())
    html += Figure(InlineImage(with_lines, o.figure_width / 2, "rectified with feature lines"),
                   "The final feature lines of M' (50_optimize/lines.json) over the texture: "
                   "text red, edges blue, page sides green");
  const std::string lines_note = LinesNote(lines);
  const cv::Mat flat = TryImage(data.ground_truth("flat.png"));
  if (!flat.empty())
    html += Figure(InlineImage(flat, o.figure_width / 2, "ground truth"),
                   "ground_truth/flat.png, the true flat page");
  page->Add(html);
  if (!lines_note.empty()) page->Add("<p>" + lines_note + "</p>");

  // Metrics of every method evaluated in 70_eval/ (docunfold, homography, oracle, ...).
  std::vector<Json> metrics;
  std::error_code ec;
  if (fs::is_directory(o.work / "70_eval", ec))
    for (const auto& e : fs::recursive_directory_iterator(o.work / "70_eval", ec))
      if (e.path().extension() == ".json") {
        Json m = TryJson(e.path());
        if (m.is_object() && m.value("format", "") == "docunfold.metrics") metrics.push_back(m);
      }
  std::sort(metrics.begin(), metrics.end(), [](const Json& a, const Json& b) {
    return a.value("method", "") < b.value("method", "");
  });
  if (!metrics.empty()) {
    std::string t =
        "<table><tr><th class=l>method</th><th>MS-SSIM</th><th>LD</th>"
        "<th>Li-D</th><th>CER</th><th>WER</th><th>surface %</th>"
        "<th>isometry</th></tr>";
    for (const Json& m : metrics) t += MetricsRow(m);
    page->Add(t +
              "</table><p>MS-SSIM as on the DocUNet benchmark; LD and Li-D from DeepFlow; "
              "CER and WER from Tesseract against the OCR of flat.png; surface: mean "
              "distance of M to the true surface in % of the page diagonal.</p>");
  }
  const Json front = TryJson(o.work / "70_eval" / "front_end.json");
  if (front.is_object() && front.value("format", "") == "docunfold.front-end-metrics")
    page->Add(FrontEndParagraph(front));
  if (metrics.empty()) {
    page->Add(data.has_ground_truth
                  ? Missing("evaluate has not run yet.")
                  : "<p>This data set has no ground truth, so nothing is measured.</p>");
  }
  page->End();
}

// The searchable PDF: a link to it, its size, and the words it holds over
// the page.
void PdfSection(const ReportOptions& o, Page* page) {
  page->Section("pdf", "The searchable PDF");
  const Json pdf = TryJson(o.work / "80_pdf/pdf.json");
  std::string summary, svg, file;
  try {
    summary = PdfSummary(pdf);
    if (!summary.empty()) {
      file = "80_pdf/" + pdf.value("/files/pdf"_json_pointer, std::string());
      svg = PdfWordsSvg(
          TryImage(o.work / "80_pdf" / pdf.value("/files/image"_json_pointer, std::string())), pdf,
          o.figure_width / 2);
    }
  } catch (const Json::exception& e) {
    throw InputError((o.work / "80_pdf/pdf.json").string() + ": " + e.what());
  }
  if (summary.empty()) {
    page->Add(Missing("pdf has not run yet."));
    page->End();
    return;
  }
  page->Add("<p><a href=\"" + MarkupEscape(file) + "\">" + MarkupEscape(file) + "</a>: " + summary +
            "</p>");
  const std::string check = PdfCheckSummary(TryJson(o.work / "70_eval/pdf.json"));
  if (!check.empty()) page->Add("<p>" + check + "</p>");
  if (!svg.empty())
    page->Add(Figure(svg,
                     "The words of the text layer in their boxes (blue; red below 0.6 "
                     "confidence), as Tesseract read them"));
  page->End();
}

void StagesSection(const ReportOptions& o, Page* page) {
  page->Section("stages", "Stages: time, memory and flags");
  const auto timings = StageTimings(o.work);
  const std::vector<std::pair<std::string, std::string>> stages = {
      {"sfm", "sfm"},          {"segment-boundary", "boundary"},
      {"densify", "points"},   {"detect-features", "features"},
      {"init-mesh", "init"},   {"optimize", "optimize"},
      {"render", "render"},    {"pdf", "pdf"},
      {"evaluate", "evaluate"}};
  std::string t =
      "<table><tr><th class=l>stage</th><th>wall time (s)</th><th>peak memory (MB)"
      "</th><th class=l>flags</th></tr>";
  double total = 0;
  for (const auto& [stage, flag_file] : stages) {
    std::string flags = ReadText(o.work / ".flags" / flag_file);
    while (!flags.empty() && std::isspace(static_cast<unsigned char>(flags.back())))
      flags.pop_back();
    auto it = timings.find(stage);
    std::string secs = "–", mem = "–";
    if (it != timings.end()) {
      secs = Fixed(it->second.value("seconds", 0.0), 1);
      mem = Fixed(it->second.value("max_rss_mb", 0.0), 0);
      total += it->second.value("seconds", 0.0);
    }
    t += "<tr><td class=l>" + stage + "</td><td>" + secs + "</td><td>" + mem +
         "</td><td class=l><code>" + MarkupEscape(flags.empty() ? "(defaults)" : flags) +
         "</code></td></tr>";
  }
  t += "<tr><th class=l>total</th><th>" + Fixed(total, 1) + "</th><th></th><th></th></tr>";
  page->Add(t +
            "</table><p>Times are those of each stage's last run (work/&lt;name&gt;/"
            "timings.jsonl). To rerun a stage with other flags: <code>make -f pipeline.mk "
            "DATA=… OPTIMIZE_FLAGS=\"…\"</code>.</p>");
  page->End();
}

}  // namespace

void DeclareOptions(OptionTable& table, ReportOptions* o) {
  table.Value("thumbnail-width", &o->thumbnail_width, "photo thumbnails (pixels)");
}

ReportResult Run(const ReportOptions& o) {
  const DataSet data = OpenDataSet(o.data);
  std::error_code ec;
  if (!fs::is_directory(o.work, ec))
    throw InputError(o.work.string() + ": no such work directory (run the pipeline first)");
  const Json cameras = TryJson(o.work / "10_sfm/cameras.json");
  Page page;
  PhotosSection(o, data, cameras, &page);
  BoundarySection(o, &page);
  fs::path mesh_dir;
  MeshSection(o, cameras, &page, &mesh_dir);
  ConvergenceSection(o, &page);
  ResultSection(o, data, mesh_dir, &page);
  PdfSection(o, &page);
  StagesSection(o, &page);

  const std::time_t now = std::time(nullptr);
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M", std::localtime(&now));
  // pipeline.mk reaches a folder of photos through WORK/.photos/images, and a
  // path Make cannot carry through WORK/.data: the report is named after the
  // data set's folder, or the photos' own folder.
  const fs::path& photos = data.photos_dir;
  const fs::path named = photos.filename() == "images" ? photos.parent_path() : photos;
  ReportResult r;
  r.html = page.Html("docunfold report: " + named.filename().string(),
                     "Photos from <code>" + MarkupEscape(photos.string()) + "</code> (" +
                         std::to_string(data.images.size()) + " files); made " + date +
                         " by docunfold " + ProgramVersion() + ".");
  return r;
}

}  // namespace docunfold::report
