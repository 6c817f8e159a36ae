#include "stages/synth/synth.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/atomic_file.h"
#include "common/cli.h"
#include "common/errors.h"
#include "common/ply.h"

namespace docunfold::synth {
namespace {

// The folded sheet sampled on a grid, placed on the table: its printed side
// facing up on average, resting at z = 0, turned to a random azimuth.
PageSurface PlaceOnTable(const FoldedSheet& sheet, double spacing, std::mt19937* rng) {
  PageSurface s;
  s.nx = std::max(2, int(std::ceil(sheet.width() / spacing)) + 1);
  s.ny = std::max(2, int(std::ceil(sheet.height() / spacing)) + 1);
  for (int r = 0; r < s.ny; ++r)
    for (int c = 0; c < s.nx; ++c) {
      const Eigen::Vector2d st(double(c) / (s.nx - 1), double(r) / (s.ny - 1));
      s.st.push_back(st);
      s.vertices.push_back(sheet.Map({st.x() * sheet.width(), st.y() * sheet.height()}));
    }
  for (int r = 0; r + 1 < s.ny; ++r)
    for (int c = 0; c + 1 < s.nx; ++c) {
      const int a = r * s.nx + c, b = a + 1, d = a + s.nx, e = d + 1;
      s.quads.push_back({a, b, e, d});
      s.triangles.push_back({a, b, e});
      s.triangles.push_back({a, e, d});
    }
  // Area-weighted mean normal of the printed side (d/dv x d/du).
  Eigen::Vector3d mean_normal = Eigen::Vector3d::Zero();
  for (const auto& q : s.quads)
    mean_normal += (s.vertices[q[3]] - s.vertices[q[0]]).cross(s.vertices[q[1]] - s.vertices[q[0]]);
  const Eigen::Matrix3d up =
      Eigen::Quaterniond::FromTwoVectors(mean_normal.normalized(), Eigen::Vector3d::UnitZ())
          .toRotationMatrix();
  const double yaw = std::uniform_real_distribution<double>(0, 2 * 3.14159265358979)(*rng);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * up;
  Eigen::Vector3d lo(1e9, 1e9, 1e9), hi(-1e9, -1e9, -1e9);
  for (Eigen::Vector3d& v : s.vertices) {
    v = R * v;
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  // Half a millimetre above the table, so the two never fight for a pixel.
  const Eigen::Vector3d shift(-(lo.x() + hi.x()) / 2, -(lo.y() + hi.y()) / 2, -lo.z() + 0.0005);
  for (Eigen::Vector3d& v : s.vertices) v += shift;
  return s;
}

Json PointsJson(const std::vector<Eigen::Vector2d>& points) {
  Json a = Json::array();
  for (const auto& p : points) a.push_back({p.x(), p.y()});
  return a;
}

}  // namespace

Json OptionsToJson(const SynthOptions& o) {
  return {{"seed", o.seed},
          {"kind", PageKindName(o.kind)},
          {"page_width_m", o.page_width_m},
          {"page_height_m", o.page_height_m},
          {"creases", o.folds.creases},
          {"crease_width_mm", {o.folds.crease_width_min * 1000, o.folds.crease_width_max * 1000}},
          {"crease_angle_deg", {o.folds.crease_angle_min, o.folds.crease_angle_max}},
          {"curl", o.folds.curl},
          {"views", o.cameras.views},
          {"width", o.cameras.width},
          {"height", o.cameras.height},
          {"hfov_deg", {o.cameras.hfov_min_deg, o.cameras.hfov_max_deg}},
          {"elevation_deg", {o.cameras.elevation_min_deg, o.cameras.elevation_max_deg}},
          {"cut_off", o.cameras.cut_off},
          {"background", BackgroundName(o.render.background)},
          {"noise_sigma", o.render.noise_sigma},
          {"jpeg_quality", o.render.jpeg_quality},
          {"flat_dpi", o.flat_dpi},
          {"texture_dpi", o.texture_dpi},
          {"mesh_spacing_mm", o.mesh_spacing_m * 1000}};
}

SynthResult Run(const SynthOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  if (o.out.empty()) throw UsageError("--out is required");
  std::error_code ec;
  if (fs::exists(o.out, ec) && !o.force)
    throw UsageError(o.out.string() + ": exists (pass --force to replace it)");
  if (o.cameras.views < 1 || o.cameras.views > 30)
    throw UsageError("--views must be between 1 and 30");

  std::mt19937 rng(o.seed);
  cv::Size2d size = DefaultPageSize(o.kind);
  if (o.page_width_m > 0) size.width = o.page_width_m;
  if (o.page_height_m > 0) size.height = o.page_height_m;

  Log("printing a " + PageKindName(o.kind) + " page");
  Page page = MakePage(o.kind, size, o.texture_dpi, &rng);
  std::vector<Fold> folds = RandomFolds(size.width, size.height, o.folds, &rng);
  if (folds.empty() && (o.folds.creases > 0 || o.folds.curl))
    throw UsageError("cannot place " + std::to_string(o.folds.creases) +
                     " non-crossing folds on this page; ask for fewer");
  FoldedSheet sheet(size.width, size.height, folds);
  PageSurface surface = PlaceOnTable(sheet, o.mesh_spacing_m, &rng);
  std::vector<PinholeCamera> cameras = MakeCameras(surface, o.cameras, &rng);
  const Lighting light = RandomLighting(&rng);
  const Table table = MakeTable(o.render.background, &rng);

  // Everything goes to a temporary folder first, renamed at the end.
  const fs::path out = fs::absolute(o.out);
  const fs::path tmp =
      out.parent_path() / ("." + out.filename().string() + ".tmp." + std::to_string(::getpid()));
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code e;
      if (!dir.empty()) fs::remove_all(dir, e);
    }
  } cleanup{tmp};
  fs::remove_all(tmp, ec);
  EnsureDirectory(tmp / "images");
  EnsureDirectory(tmp / "ground_truth");

  Progress progress("rendering views", long(cameras.size()));
  for (size_t i = 0; i < cameras.size(); ++i) {
    cv::Mat photo = RenderView(surface, page.image, table, light, cameras[i]);
    AddSensorEffects(&photo, o.render, &rng);
    WriteImageAtomic(tmp / "images" / cameras[i].image, photo,
                     {cv::IMWRITE_JPEG_QUALITY, o.render.jpeg_quality});
    progress.Update(long(i + 1));
  }
  progress.Done();

  // Ground truth.
  const double flat_ppm = o.flat_dpi / 0.0254;
  const cv::Size flat_size(int(std::lround(size.width * flat_ppm)),
                           int(std::lround(size.height * flat_ppm)));
  cv::Mat flat;
  cv::resize(page.image, flat, flat_size, 0, 0, cv::INTER_AREA);
  WriteImageAtomic(tmp / "ground_truth/flat.png", flat, {cv::IMWRITE_PNG_COMPRESSION, 9});

  std::string text;
  for (const std::string& line : page.text) text += line + "\n";
  WriteTextAtomic(tmp / "ground_truth/text.txt", text);

  Json page_json = MakeHeader("docunfold.gt-page", 1, "synth");
  page_json["width_m"] = size.width;
  page_json["height_m"] = size.height;
  WriteJsonAtomic(tmp / "ground_truth/page.json", page_json);

  Json cams = MakeHeader("docunfold.gt-cameras", 1, "synth");
  cams["convention"] =
      "x_cam = R x_world + t; OpenCV axes (x right, y down, z forward); pixel centres at "
      "integer coordinates; metres";
  cams["views"] = Json::array();
  for (const PinholeCamera& c : cameras) cams["views"].push_back(CameraToJson(c));
  WriteJsonAtomic(tmp / "ground_truth/cameras.json", cams);

  PlyData mesh;
  mesh.comments = {"true page surface, world frame, metres",
                   "s,t = column and row of flat.png as fractions, (0,0) top left",
                   "made by docunfold synth seed " + std::to_string(o.seed)};
  mesh.vertices = surface.vertices;
  std::vector<double> s, t;
  for (const auto& st : surface.st) {
    s.push_back(st.x());
    t.push_back(st.y());
  }
  mesh.SetProperty("s", s);
  mesh.SetProperty("t", t);
  mesh.faces = surface.quads;
  mesh.SetGridSize(surface.nx, surface.ny);
  WritePly(tmp / "ground_truth/mesh.ply", mesh);

  // True lines in flat.png pixels (centres at integer coordinates).
  Json features = MakeHeader("docunfold.gt-features", 1, "synth");
  features["width"] = flat_size.width;
  features["height"] = flat_size.height;
  features["lines"] = Json::array();
  for (const PageLine& l : page.lines) {
    std::vector<Eigen::Vector2d> px;
    for (const Eigen::Vector2d& p : l.points)
      px.emplace_back(p.x() / size.width * flat_size.width - 0.5,
                      p.y() / size.height * flat_size.height - 0.5);
    features["lines"].push_back({{"kind", l.kind}, {"points", PointsJson(px)}});
  }
  WriteJsonAtomic(tmp / "ground_truth/features.json", features);

  Json options = MakeHeader("docunfold.synth-options", 1, "synth", OptionsToJson(o));
  options["folds"] = Json::array();
  for (const Fold& f : folds)
    options["folds"].push_back({{"point_m", {f.point.x(), f.point.y()}},
                                {"direction", {f.direction.x(), f.direction.y()}},
                                {"width_mm", f.width * 1000},
                                {"angle_deg", f.angle * 180 / 3.14159265358979}});
  WriteJsonAtomic(tmp / "ground_truth/synth.json", options);
  if (!o.command_line.empty()) WriteTextAtomic(tmp / "COMMAND", o.command_line + "\n");

  if (fs::exists(out, ec)) fs::remove_all(out, ec);
  fs::rename(tmp, out, ec);
  if (ec)
    throw OutputError(out.string() + ": cannot move the data set into place: " + ec.message());
  cleanup.dir.clear();

  SynthResult r;
  r.views = int(cameras.size());
  r.mesh_vertices = int(surface.vertices.size());
  r.folds = int(folds.size());
  r.seconds = SecondsSince(start);
  return r;
}

}  // namespace docunfold::synth
