#include "tests/render/render_fixtures.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/atomic_file.h"
#include "common/json_io.h"
#include "common/raster.h"
#include "tests/support/test_support.h"
#include "tests/support/truth_frame.h"

namespace docunfold::testing {
namespace {

bool Inside(const Eigen::Vector2d& p, int width, int height) {
  return p.x() >= 0 && p.y() >= 0 && p.x() <= width - 1 && p.y() <= height - 1;
}

Json Points(const std::vector<Eigen::Vector2d>& pts) {
  Json a = Json::array();
  for (const auto& p : pts) a.push_back({p.x(), p.y()});
  return a;
}

// The part of a projected border inside the image. It is a real side when
// most of it is inside (the page edge is seen, only its end is cut off);
// otherwise the image border stands in for it, not real.
std::vector<Eigen::Vector2d> ClipToImage(const std::vector<Eigen::Vector2d>& pts, int width,
                                         int height, bool* real) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : pts)
    if (Inside(p, width, height)) out.push_back(p);
  *real = out.size() >= 2 && out.size() * 2 >= pts.size();
  if (!*real) {
    out.clear();
    for (const auto& p : pts)
      out.emplace_back(std::clamp(p.x(), 0.0, width - 1.0), std::clamp(p.y(), 0.0, height - 1.0));
  }
  return out;
}

}  // namespace

std::vector<fs::path> RenderDataSets() {
  std::vector<fs::path> sets;
  for (const fs::path& base : {SourceDir() / "samples", RealisticDir()}) {
    std::error_code ec;
    if (base.empty() || !fs::is_directory(base, ec)) continue;
    for (const auto& e : fs::directory_iterator(base))
      if (fs::is_regular_file(e.path() / "ground_truth" / "mesh.ply") &&
          fs::is_regular_file(e.path() / "ground_truth" / "flat.png"))
        sets.push_back(e.path());
  }
  std::sort(sets.begin(), sets.end());
  return sets;
}

void WriteBoundaryJson(const fs::path& file, int width, int height,
                       const std::array<std::vector<Eigen::Vector2d>, 4>& sides,
                       const std::array<bool, 4>& real) {
  Json doc = MakeHeader("docunfold.boundary", 1, "render-test");
  doc["image"] = "reference.png";
  doc["width"] = width;
  doc["height"] = height;
  std::vector<Eigen::Vector2d> contour;
  for (const auto& p : sides[0]) contour.push_back(p);
  for (const auto& p : sides[1]) contour.push_back(p);
  for (auto it = sides[2].rbegin(); it != sides[2].rend(); ++it) contour.push_back(*it);
  for (auto it = sides[3].rbegin(); it != sides[3].rend(); ++it) contour.push_back(*it);
  doc["contour"] = Points(contour);
  doc["corners"] = Points({sides[0].front(), sides[0].back(), sides[2].back(), sides[2].front()});
  const char* names[4] = {"top", "right", "bottom", "left"};
  doc["sides"] = Json::object();
  for (int i = 0; i < 4; ++i)
    doc["sides"][names[i]] = {{"points", Points(sides[i])}, {"real", real[i]}};
  WriteJsonAtomic(file, doc);
}

TruthInputs MakeTruthInputs(const GroundTruth& gt) {
  const std::string reference = gt.cameras.views[0].image;
  const CameraSet cams = CamerasInReferenceFrame(gt, reference);
  TruthInputs out;
  out.camera = *cams.Find(reference);
  out.photo = ReadImage(gt.root / "images" / reference);
  const TrueMeshes truth = TrueMeshesInReferenceFrame(gt, reference);
  const auto grid = truth.mesh3d.GridSize();
  if (!grid) throw std::runtime_error(gt.root.string() + ": true mesh has no grid comment");
  out.meshes.grid = {(*grid)[0], (*grid)[1]};
  out.meshes.mesh3d = truth.mesh3d.vertices;
  for (const auto& v : truth.mesh2d.vertices) out.meshes.mesh2d.push_back(v.head<2>());
  // Page outline: border vertices of the true grid ordered along each side.
  const auto& s = gt.mesh.FindProperty("s")->values;
  const auto& t = gt.mesh.FindProperty("t")->values;
  std::array<std::vector<std::pair<double, Eigen::Vector2d>>, 4> border;
  for (size_t i = 0; i < s.size(); ++i) {
    const Eigen::Vector2d px = out.camera.Project(truth.mesh3d.vertices[i]);
    if (t[i] < 1e-6) border[0].push_back({s[i], px});
    if (s[i] > 1 - 1e-6) border[1].push_back({t[i], px});
    if (t[i] > 1 - 1e-6) border[2].push_back({s[i], px});
    if (s[i] < 1e-6) border[3].push_back({t[i], px});
  }
  for (int k = 0; k < 4; ++k) {
    std::sort(border[k].begin(), border[k].end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<Eigen::Vector2d> pts;
    for (const auto& e : border[k]) pts.push_back(e.second);
    bool real = false;
    out.sides[k] = ClipToImage(pts, out.camera.width, out.camera.height, &real);
    out.real[k] = real;
  }
  return out;
}

namespace {

render::RenderInputs Inputs(const PinholeCamera& camera, const cv::Mat3b& photo,
                            const MeshPair& meshes,
                            const std::array<std::vector<Eigen::Vector2d>, 4>& sides,
                            const std::array<bool, 4>& real) {
  render::RenderInputs in;
  in.camera = camera;
  in.reference = photo;
  in.boundary.file = "boundary.json";
  in.boundary.width = camera.width;
  in.boundary.height = camera.height;
  for (int i = 0; i < 4; ++i) {
    in.boundary.sides[i].points = sides[i];
    in.boundary.sides[i].real = real[i];
  }
  // The outline: top TL->TR, right TR->BR, bottom BR->BL, left BL->TL.
  auto& contour = in.boundary.contour;
  contour.insert(contour.end(), sides[0].begin(), sides[0].end());
  contour.insert(contour.end(), sides[1].begin(), sides[1].end());
  contour.insert(contour.end(), sides[2].rbegin(), sides[2].rend());
  contour.insert(contour.end(), sides[3].rbegin(), sides[3].rend());
  in.meshes = meshes;
  in.cameras_file = "cameras.json";
  in.reference_file = "reference.png";
  in.meshes_dir = "meshes";
  return in;
}

}  // namespace

render::RenderInputs InputsOf(const SyntheticScene& s) {
  return Inputs(s.camera, s.photo, s.meshes, s.sides, s.real);
}

render::RenderInputs InputsOf(const TruthInputs& t) {
  return Inputs(t.camera, t.photo, t.meshes, t.sides, t.real);
}

cv::Mat3b MakeTexture(int width, int height) {
  cv::Mat3b tex(height, width, cv::Vec3b(236, 240, 242));
  std::mt19937 rng(7);
  const char* words[] = {"rectify", "crease",    "page", "isometry", "mesh",
                         "render",  "docunfold", "fold", "text",     "line"};
  const double font = width / 900.0;
  const int line_h = std::max(10, int(height / 40.0));
  for (int y = line_h * 3; y < height * 2 / 3; y += line_h) {
    std::string line;
    for (int w = 0; w < 12; ++w) line += std::string(words[rng() % 10]) + " ";
    cv::putText(tex, line, cv::Point(width / 20, y), cv::FONT_HERSHEY_SIMPLEX, font,
                cv::Scalar(30, 30, 30), std::max(1, int(font * 2)), cv::LINE_AA);
  }
  // Table rules and a frame.
  for (int y = height * 2 / 3 + 10; y < height - 20; y += line_h)
    cv::line(tex, cv::Point(width / 20, y), cv::Point(width * 19 / 20, y), cv::Scalar(60, 40, 20),
             2);
  // The frame is printed where a printer's margin would be, clear of the
  // few pixels along the page's edge that render does not take from the
  // photo (page_edge.h).
  cv::rectangle(tex, cv::Rect(20, 20, width - 40, height - 40), cv::Scalar(90, 60, 30), 3);
  // Fine stripes (period 3 texture pixels) in a corner patch.
  for (int y = height - 120; y < height - 30; ++y)
    for (int x = width * 2 / 3; x < width - 30; ++x)
      if ((x / 1) % 3 == 0) tex(y, x) = cv::Vec3b(20, 20, 20);
  return tex;
}

SyntheticScene MakeScene(const SceneOptions& o) {
  SyntheticScene s;
  s.texture = MakeTexture(o.texture_width, o.texture_height);
  s.page_w = o.page_w;
  s.page_h = o.page_h;
  s.camera.image = "view_00.png";
  s.camera.width = o.image_width;
  s.camera.height = o.image_height;
  s.camera.K << o.focal, 0, (o.image_width - 1) / 2.0, 0, o.focal, (o.image_height - 1) / 2.0, 0, 0,
      1;
  const int nx = 43, ny = 57;
  s.meshes.grid = {nx, ny};
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(o.tilt_deg * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      const double a = o.page_w * c / (nx - 1), b = o.page_h * r / (ny - 1);
      Eigen::Vector3d local(a, b, 0);
      const double half = o.page_w / 2;
      if (o.radius > 0 && a > half) {
        const double theta = (a - half) / o.radius;
        local = {half + o.radius * std::sin(theta), b, -o.radius * (1 - std::cos(theta))};
      }
      s.meshes.mesh3d.push_back(o.page_origin + tilt * local);
      s.meshes.mesh2d.emplace_back(a, b);
    }
  // The photo: 3x3 supersampled texture lookup over a plain table.
  const double ss = 3;
  const auto tris = s.meshes.grid.Triangles();
  const RasterResult raster = RasterizeMesh(s.camera, s.meshes.mesh3d, tris, ss);
  Eigen::MatrixXf uv(s.meshes.mesh2d.size(), 2);
  for (size_t i = 0; i < s.meshes.mesh2d.size(); ++i) {
    uv(i, 0) = float(s.meshes.mesh2d[i].x() / o.page_w * o.texture_width - 0.5);
    uv(i, 1) = float(s.meshes.mesh2d[i].y() / o.page_h * o.texture_height - 0.5);
  }
  cv::Mat map = InterpolateAttributes(raster, tris, uv);
  cv::Mat3b big;
  cv::remap(s.texture, big, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar(70, 110, 60));
  cv::resize(big, s.photo, cv::Size(o.image_width, o.image_height), 0, 0, cv::INTER_AREA);
  // Sides: the projected border of the grid.
  std::array<std::vector<Eigen::Vector2d>, 4> border;
  for (int c = 0; c < nx; ++c) {
    border[0].push_back(s.camera.Project(s.meshes.mesh3d[s.meshes.grid.Index(0, c)]));
    border[2].push_back(s.camera.Project(s.meshes.mesh3d[s.meshes.grid.Index(ny - 1, c)]));
  }
  for (int r = 0; r < ny; ++r) {
    border[1].push_back(s.camera.Project(s.meshes.mesh3d[s.meshes.grid.Index(r, nx - 1)]));
    border[3].push_back(s.camera.Project(s.meshes.mesh3d[s.meshes.grid.Index(r, 0)]));
  }
  for (int k = 0; k < 4; ++k) {
    bool real = false;
    s.sides[k] = ClipToImage(border[k], o.image_width, o.image_height, &real);
    s.real[k] = real;
  }
  return s;
}

void WriteScene(const SyntheticScene& scene, const fs::path& work) {
  EnsureDirectory(work / "10_sfm");
  PinholeCamera other = scene.camera;
  other.image = "view_01.png";
  other.t = Eigen::Vector3d(-0.2, 0, 0);
  Json doc = MakeHeader("docunfold.cameras", 1, "render-test");
  doc["reference"] = scene.camera.image;
  doc["views"] = {CameraToJson(scene.camera), CameraToJson(other)};
  WriteJsonAtomic(work / "10_sfm" / "cameras.json", doc);
  WriteImageAtomic(work / "10_sfm" / "reference.png", scene.photo);
  EnsureDirectory(work / "20_boundary");
  WriteBoundaryJson(work / "20_boundary" / "boundary.json", scene.camera.width, scene.camera.height,
                    scene.sides, scene.real);
  EnsureDirectory(work / "40_init");
  WriteMeshPair(work / "40_init", scene.meshes);
}

TileOffsets FindTileOffsets(const cv::Mat1f& ref, const cv::Mat1f& moved, const cv::Mat1b& mask,
                            int tile, int radius) {
  TileOffsets out;
  std::vector<double> offsets;
  for (int y = radius; y + tile + radius <= ref.rows; y += tile)
    for (int x = radius; x + tile + radius <= ref.cols; x += tile) {
      const cv::Rect window(x - radius, y - radius, tile + 2 * radius, tile + 2 * radius);
      if (!mask.empty() && cv::countNonZero(mask(window)) < window.area()) continue;
      const cv::Rect r(x, y, tile, tile);
      cv::Scalar mean, sd;
      cv::meanStdDev(ref(r), mean, sd);
      if (sd[0] < 0.1) continue;  // blank paper
      ++out.tiles;
      cv::Mat1f score;
      cv::matchTemplate(moved(window), ref(r), score, cv::TM_CCOEFF_NORMED);
      double best;
      cv::Point p;
      cv::minMaxLoc(score, nullptr, &best, nullptr, &p);
      if (best < 0.5) continue;
      // A tile with one direction of structure only (a rule, a table line)
      // matches all along it: such tiles say nothing about the offset.
      cv::Mat1f others = score.clone();
      cv::circle(others, p, 3, cv::Scalar(-1), cv::FILLED);
      double second;
      cv::minMaxLoc(others, nullptr, &second);
      if (best - second < 0.05) {
        --out.tiles;
        continue;
      }
      ++out.matched;
      // Parabola through the peak and its neighbours, per axis.
      auto refine = [](float l, float c, float r) {
        const float d = l - 2 * c + r;
        return d < 0 ? 0.5f * (l - r) / d : 0.0f;
      };
      double dx = p.x - radius, dy = p.y - radius;
      if (p.x > 0 && p.x + 1 < score.cols)
        dx += refine(score(p.y, p.x - 1), score(p.y, p.x), score(p.y, p.x + 1));
      if (p.y > 0 && p.y + 1 < score.rows)
        dy += refine(score(p.y - 1, p.x), score(p.y, p.x), score(p.y + 1, p.x));
      offsets.push_back(std::hypot(dx, dy));
    }
  if (offsets.empty()) return out;
  std::sort(offsets.begin(), offsets.end());
  out.median = offsets[offsets.size() / 2];
  out.p90 = offsets[offsets.size() * 9 / 10];
  out.max = offsets.back();
  return out;
}

}  // namespace docunfold::testing
