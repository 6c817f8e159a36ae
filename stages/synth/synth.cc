#include "stages/synth/synth.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/option_table.h"
#include "common/ply.h"
#include "common/program.h"
#include "stages/synth/random.h"

namespace docunfold::synth {
namespace {

// The folded sheet sampled on a grid, placed on the table: its printed side
// facing up on average (or, with `root_flat`, the panel holding the page
// centre lying flat, print up: a flap, a steep end or a curled end would tilt
// the average), resting at z = 0, turned to a random azimuth.
PageSurface PlaceOnTable(const FoldedSheet& sheet, double spacing, bool root_flat,
                         std::mt19937* rng) {
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
  // FoldedSheet leaves the root panel in z = 0 with its print facing -z.
  const Eigen::Matrix3d up =
      root_flat
          ? Eigen::Matrix3d(Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()))
          : Eigen::Quaterniond::FromTwoVectors(mean_normal.normalized(), Eigen::Vector3d::UnitZ())
                .toRotationMatrix();
  const double yaw = Uniform(rng, 0, 2 * 3.14159265358979);
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

// A length given in millimetres, kept in metres.
std::string ParseMillimetres(const std::string& text, double* metres) {
  double mm = 0;
  if (!CLI::detail::lexical_cast(text, mm))
    return "expected a length in millimetres, got '" + text + "'";
  *metres = mm / 1000;
  return "";
}

std::string FormatMillimetres(const double& metres) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", metres * 1000);
  return buf;
}

// WxH in millimetres, kept in metres.
std::string ParsePageSize(const std::string& text, cv::Size2d* size_m) {
  double w = 0, h = 0;
  if (std::sscanf(text.c_str(), "%lfx%lf", &w, &h) != 2 || w <= 0 || h <= 0)
    return "expected WxH in millimetres, e.g. 210x297";
  size_m->width = w / 1000;
  size_m->height = h / 1000;
  return "";
}

std::string FormatPageSize(const cv::Size2d& size_m) {
  if (size_m.width <= 0 || size_m.height <= 0) return "";
  return FormatMillimetres(size_m.width) + "x" + FormatMillimetres(size_m.height);
}

// What the photos show: the printed page, folded, on the table, and the
// cameras and light. Made in this order from one generator.
struct Scene {
  cv::Size2d size;  // of the page, metres
  Page page;
  std::vector<Fold> folds;
  PageSurface surface;
  std::vector<PinholeCamera> cameras;
  Lighting light;
  Table table;
};

Scene MakeScene(const SynthOptions& o, std::mt19937* rng) {
  Scene scene;
  cv::Size2d& size = scene.size;
  size = DefaultPageSize(o.kind);
  // A receipt torn off a roll is as wide as the roll, and as long as the
  // till made it.
  if (o.roll_mm > 0) size = {o.roll_mm / 1000.0, Uniform(rng, 0.14, 0.24)};
  if (o.page_size_m.width > 0) size.width = o.page_size_m.width;
  if (o.page_size_m.height > 0) size.height = o.page_size_m.height;

  Log("printing a " + PageKindName(o.kind) + " page");
  scene.page = MakePage(o.kind, size, o.texture_dpi, rng, o.roll_mm);
  std::vector<Fold> shaped;
  try {
    shaped = ShapeFolds(size.width, size.height, o.shapes, o.folds, rng);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  scene.folds = RandomFolds(size.width, size.height, o.folds, rng, shaped);
  if (scene.folds.empty() && (o.folds.creases > 0 || o.folds.curl || o.shapes.any()))
    throw UsageError("cannot place " + std::to_string(o.folds.creases) +
                     " non-crossing folds on this page" +
                     (o.shapes.any() ? " beside the flap, steep fold or end curl" : "") +
                     " without the page passing through itself; ask for fewer");
  FoldedSheet sheet(size.width, size.height, scene.folds);
  scene.surface = PlaceOnTable(sheet, o.mesh_spacing_m, o.shapes.any(), rng);
  scene.cameras = MakeCameras(scene.surface, o.cameras, rng);
  scene.light = RandomLighting(rng);
  scene.table = MakeTable(o.render.background, rng);
  return scene;
}

// images/view_NN.jpg: every camera's photo, with sensor effects.
void WritePhotos(const Scene& scene, const RenderOptions& render, const fs::path& dir,
                 std::mt19937* rng) {
  Progress progress("rendering views", long(scene.cameras.size()));
  for (size_t i = 0; i < scene.cameras.size(); ++i) {
    cv::Mat photo =
        RenderView(scene.surface, scene.page.image, scene.table, scene.light, scene.cameras[i]);
    AddSensorEffects(&photo, render, rng);
    WriteImageAtomic(dir / "images" / scene.cameras[i].image, photo,
                     {cv::IMWRITE_JPEG_QUALITY, render.jpeg_quality});
    progress.Update(long(i + 1));
  }
  progress.Done();
}

// ground_truth/mesh.ply: the true surface with each vertex's s, t.
void WriteTrueMesh(const PageSurface& surface, uint32_t seed, const fs::path& path) {
  PlyData mesh;
  mesh.comments = {"true page surface, world frame, metres",
                   "s,t = column and row of flat.png as fractions, (0,0) top left",
                   "made by docunfold synth seed " + std::to_string(seed)};
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
  WritePly(path, mesh);
}

// ground_truth/: flat.png, text.txt, page.json, cameras.json, mesh.ply,
// features.json and synth.json.
void WriteGroundTruth(const Scene& scene, const SynthOptions& o, const Json& options_record,
                      const fs::path& dir) {
  const cv::Size2d& size = scene.size;
  const double flat_ppm = o.flat_dpi / 0.0254;
  const cv::Size flat_size(int(std::lround(size.width * flat_ppm)),
                           int(std::lround(size.height * flat_ppm)));
  cv::Mat flat;
  cv::resize(scene.page.image, flat, flat_size, 0, 0, cv::INTER_AREA);
  WriteImageAtomic(dir / "flat.png", flat, {cv::IMWRITE_PNG_COMPRESSION, 9});

  std::string text;
  for (const std::string& line : scene.page.text) text += line + "\n";
  WriteTextAtomic(dir / "text.txt", text);

  Json page_json = MakeHeader("docunfold.gt-page", 1, "synth");
  page_json["width_m"] = size.width;
  page_json["height_m"] = size.height;
  WriteJsonAtomic(dir / "page.json", page_json);

  Json cams = MakeHeader("docunfold.gt-cameras", 1, "synth");
  cams["convention"] =
      "x_cam = R x_world + t; OpenCV axes (x right, y down, z forward); pixel centres at "
      "integer coordinates; metres";
  cams["views"] = Json::array();
  for (const PinholeCamera& c : scene.cameras) cams["views"].push_back(CameraToJson(c));
  WriteJsonAtomic(dir / "cameras.json", cams);

  WriteTrueMesh(scene.surface, o.seed, dir / "mesh.ply");

  // True lines in flat.png pixels (centres at integer coordinates).
  Json features = MakeHeader("docunfold.gt-features", 1, "synth");
  features["width"] = flat_size.width;
  features["height"] = flat_size.height;
  features["lines"] = Json::array();
  for (const PageLine& l : scene.page.lines) {
    std::vector<Eigen::Vector2d> px;
    for (const Eigen::Vector2d& p : l.points)
      px.emplace_back(p.x() / size.width * flat_size.width - 0.5,
                      p.y() / size.height * flat_size.height - 0.5);
    features["lines"].push_back({{"kind", l.kind}, {"points", PointsJson(px)}});
  }
  WriteJsonAtomic(dir / "features.json", features);

  Json options = MakeHeader("docunfold.synth-options", 1, "synth", options_record);
  options["folds"] = Json::array();
  for (const Fold& f : scene.folds)
    options["folds"].push_back({{"point_m", {f.point.x(), f.point.y()}},
                                {"direction", {f.direction.x(), f.direction.y()}},
                                {"width_mm", f.width * 1000},
                                {"angle_deg", f.angle * 180 / 3.14159265358979}});
  WriteJsonAtomic(dir / "synth.json", options);
}

}  // namespace

void DeclareOptions(OptionTable& table, SynthOptions* o) {
  table.Switch("force", &o->force, "replace an existing folder");
  table.Value("seed", &o->seed, "random seed");
  std::vector<std::pair<std::string, PageKind>> kinds;
  for (PageKind k : {PageKind::kText, PageKind::kTable, PageKind::kReceipt, PageKind::kPoster})
    kinds.emplace_back(PageKindName(k), k);
  table.Choice("kind", &o->kind, kinds, "the page");
  table.Parsed<cv::Size2d>(
      "page-size", &o->page_size_m, "WxH", ParsePageSize, FormatPageSize,
      "page size in mm (default: A4, receipt 80x200, a --roll receipt the roll's width by "
      "140 to 240)");
  table.Choice("roll", &o->roll_mm, {{"none", 0}, {"58", 58}, {"80", 80}},
               "receipt only: the till roll's width in mm; prints the receipt as a till does "
               "(32 or 48 monospaced columns, prices right-aligned, separator rows, TOTAL, "
               "footer); none keeps the older, plainer receipt");
  table.Value("creases", &o->folds.creases, "number of narrow folds");
  table.Parsed<double>("crease-width-mm", &o->folds.crease_width_min, "MM", ParseMillimetres,
                       FormatMillimetres, "narrowest crease (mm)");
  table.Parsed<double>("crease-width-max-mm", &o->folds.crease_width_max, "MM", ParseMillimetres,
                       FormatMillimetres,
                       "widest crease (mm); below --crease-width-mm means that width");
  table.Value("angle-min", &o->folds.crease_angle_min, 0.0, 180.0,
              "smallest crease angle (degrees)");
  table.Value("angle-max", &o->folds.crease_angle_max, 0.0, 180.0,
              "largest crease angle (degrees); over 125 a fold set is kept only if the page "
              "does not pass through itself");
  table.Switch("curl", &o->folds.curl, "add one wide bend (a curl of several cm)");
  table.Choice("flap", &o->shapes.flap,
               {{"none", Flap::kNone}, {"corner", Flap::kCorner}, {"end", Flap::kEnd}},
               "fold a corner or an end of the page back over it (its blank back up)");
  table.Value("flap-angle", &o->shapes.flap_angle, 90.0, 180.0,
              "how far the flap turns (degrees; 180 lies on the page)");
  table.Value("steep-fold", &o->shapes.steep_angle, 0.0, 170.0,
              "add a crease near an end bent up by this angle (degrees; over 90 the end panel "
              "leans back over the page; 0: none)");
  table.Choice("end-curl", &o->shapes.end_curl,
               {{"none", PageEnd::kNone},
                {"top", PageEnd::kTop},
                {"bottom", PageEnd::kBottom},
                {"both", PageEnd::kBoth}},
               "curl an end of the page up off the table, tightest at the edge");
  table.Parsed<double>("end-curl-length-mm", &o->shapes.end_curl_length, "MM", ParseMillimetres,
                       FormatMillimetres, "length of the page that curls (mm)");
  table.Value("end-curl-angle", &o->shapes.end_curl_angle, 1.0, 270.0,
              "how far a curled end turns in all (degrees)");
  table.Value("views", &o->cameras.views, 1, 30, "number of photos");
  table.Value("width", &o->cameras.width, 64, std::numeric_limits<int>::max(),
              "image width (pixels)");
  table.Value("height", &o->cameras.height, 64, std::numeric_limits<int>::max(),
              "image height (pixels)");
  table.Value("elevation-min", &o->cameras.elevation_min_deg, "lowest camera elevation (degrees)");
  table.Value("elevation-max", &o->cameras.elevation_max_deg, "highest camera elevation (degrees)");
  table.Switch("cut-off", &o->cameras.cut_off,
               "frame every view so that part of the page is outside the image");
  std::vector<std::pair<std::string, Background>> backgrounds;
  for (Background b :
       {Background::kPlain, Background::kWood, Background::kCloth, Background::kGranite})
    backgrounds.emplace_back(BackgroundName(b), b);
  table.Choice("background", &o->render.background, backgrounds, "the table");
  table.Value("noise", &o->render.noise_sigma, "sensor noise (grey levels)");
  table.Value("jpeg-quality", &o->render.jpeg_quality, "JPEG quality");
  table.Value("flat-dpi", &o->flat_dpi, "resolution of flat.png (dpi)");
  table.Parsed<double>("mesh-spacing-mm", &o->mesh_spacing_m, "MM", ParseMillimetres,
                       FormatMillimetres, "vertex spacing of mesh.ply (mm)");
}

SynthResult Run(const SynthOptions& o, const Json& options_record) {
  const auto start = std::chrono::steady_clock::now();
  if (o.out.empty()) throw UsageError("--out is required");
  std::error_code ec;
  if (fs::exists(o.out, ec) && !o.force)
    throw UsageError(o.out.string() + ": exists (pass --force to replace it)");
  if (o.cameras.views < 1 || o.cameras.views > 30)
    throw UsageError("--views must be between 1 and 30");
  if (o.roll_mm > 0 && o.kind != PageKind::kReceipt)
    throw UsageError("--roll is for --kind receipt");
  if (o.shapes.end_curl_length <= 0) throw UsageError("--end-curl-length-mm must be positive");

  std::mt19937 rng(o.seed);
  const Scene scene = MakeScene(o, &rng);

  // Everything goes to a folder beside --out first, put in its place at the end.
  AtomicDirectory staging(o.out);
  const fs::path& tmp = staging.path();
  EnsureDirectory(tmp / "images");
  EnsureDirectory(tmp / "ground_truth");

  WritePhotos(scene, o.render, tmp, &rng);
  WriteGroundTruth(scene, o, options_record, tmp / "ground_truth");
  if (!o.command_line.empty()) WriteTextAtomic(tmp / "COMMAND", o.command_line + "\n");
  staging.Commit();

  SynthResult r;
  r.views = int(scene.cameras.size());
  r.mesh_vertices = int(scene.surface.vertices.size());
  r.folds = int(scene.folds.size());
  r.seconds = SecondsSince(start);
  return r;
}

}  // namespace docunfold::synth
