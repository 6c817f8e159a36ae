#include "stages/baseline/baseline.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/atomic_file.h"
#include "common/dataset.h"
#include "common/errors.h"
#include "common/json_io.h"
#include "common/option_table.h"
#include "common/photo.h"
#include "common/program.h"
#include "common/raster.h"
#include "common/shading.h"
#include "common/statistics.h"

namespace docunfold::baseline {
namespace {

constexpr int kMaxSupersampling = 4;

// Supersampling factor for a mapping whose output pixels cover `footprint`
// source pixels (the larger side of a pixel's image): 1 when magnifying.
int Supersampling(double footprint) {
  if (!(footprint > 1.2)) return 1;
  return std::min(kMaxSupersampling, int(std::ceil(footprint)));
}

double SideLength(const Corners& c, int a, int b) { return (c[a] - c[b]).norm(); }

// Fills pixels where the map is NaN with the value of the nearest valid one
// (pixels on the very border of the page may miss every triangle).
void FillHoles(cv::Mat2f& map) {
  cv::Mat1b holes(map.size());
  int count = 0;
  for (int y = 0; y < map.rows; ++y)
    for (int x = 0; x < map.cols; ++x) {
      const bool hole = !std::isfinite(map(y, x)[0]) || !std::isfinite(map(y, x)[1]);
      holes(y, x) = hole ? 255 : 0;
      count += hole;
    }
  if (count == 0) return;
  if (count == int(map.total()))
    throw std::runtime_error("the true surface covers no pixel of the output");
  cv::Mat1f distance;
  cv::Mat1i labels;
  cv::distanceTransform(holes, distance, labels, cv::DIST_L2, cv::DIST_MASK_5,
                        cv::DIST_LABEL_PIXEL);
  std::vector<cv::Vec2f> value_of_label(map.total() + 1);
  for (int y = 0; y < map.rows; ++y)
    for (int x = 0; x < map.cols; ++x)
      if (!holes(y, x)) value_of_label[labels(y, x)] = map(y, x);
  for (int y = 0; y < map.rows; ++y)
    for (int x = 0; x < map.cols; ++x)
      if (holes(y, x)) map(y, x) = value_of_label[labels(y, x)];
}

// Photo pixel seen at each pixel of the flat page rendered at
// `size` * `scale`: rasterize the true mesh in (s, t) space, interpolate the
// 3D point, project it with the true camera. NaN where the mesh is absent.
cv::Mat2f TrueMap(const PinholeCamera& camera, const PlyData& mesh,
                  const std::vector<Triangle>& triangles, cv::Size size, int scale) {
  const auto& s = mesh.FindProperty("s")->values;
  const auto& t = mesh.FindProperty("t")->values;
  const int w = size.width * scale, h = size.height * scale;
  std::vector<Eigen::Vector3d> screen(mesh.vertices.size());
  for (size_t i = 0; i < screen.size(); ++i) screen[i] = {s[i] * w - 0.5, t[i] * h - 0.5, 1.0};
  const RasterResult raster = Rasterize(screen, triangles, w, h);
  cv::Mat2f map(h, w, cv::Vec2f(NAN, NAN));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int f = raster.face(y, x);
      if (f < 0) continue;
      const double b1 = raster.bary(y, x)[0], b2 = raster.bary(y, x)[1];
      const Triangle& tri = triangles[f];
      const Eigen::Vector3d p = (1 - b1 - b2) * mesh.vertices[tri[0]] + b1 * mesh.vertices[tri[1]] +
                                b2 * mesh.vertices[tri[2]];
      const Eigen::Vector3d xc = camera.CamFromWorld(p);
      if (xc.z() <= 0) continue;
      const Eigen::Vector2d px = camera.ProjectCam(xc);
      map(y, x) = cv::Vec2f(float(px.x()), float(px.y()));
    }
  }
  return map;
}

// 95th percentile of the larger side of each pixel's footprint in the source.
double MapFootprint(const cv::Mat2f& map) {
  std::vector<double> sizes;
  for (int y = 0; y + 1 < map.rows; y += 2)
    for (int x = 0; x + 1 < map.cols; x += 2) {
      const cv::Vec2f a = map(y, x), dx = map(y, x + 1) - a, dy = map(y + 1, x) - a;
      const double fx = std::hypot(dx[0], dx[1]), fy = std::hypot(dy[0], dy[1]);
      if (std::isfinite(fx) && std::isfinite(fy)) sizes.push_back(std::max(fx, fy));
    }
  if (sizes.empty()) return 1;
  const size_t rank = size_t(0.95 * double(sizes.size() - 1));
  return NthSmallest(std::move(sizes), rank);
}

fs::path MustExist(const fs::path& p, const std::string& why) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) throw InputError(p.string() + ": no such file (" + why + ")");
  return p;
}

Corners ReadCorners(const fs::path& path) {
  const Json doc = ReadJsonFile(path);
  CheckFormat(doc, path, "docunfold.boundary", 1);
  JsonReader r(doc, path);
  const Json& corners = r.At("/corners");
  if (!corners.is_array() || corners.size() != 4)
    r.Fail("/corners", "four corners [x, y] expected (TL, TR, BR, BL)");
  Corners out;
  for (int i = 0; i < 4; ++i) {
    const std::string p = "/corners/" + std::to_string(i);
    out[i] = {r.Number(p + "/0"), r.Number(p + "/1")};
    if (!out[i].allFinite()) r.Fail(p, "not finite");
  }
  // A quadrilateral with (nearly) no area has no page in it.
  double area = 0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d a = out[i], b = out[(i + 1) % 4];
    area += a.x() * b.y() - b.x() * a.y();
  }
  if (std::abs(area) / 2 < 16) r.Fail("/corners", "corners enclose no area");
  return out;
}

double PageAspect(const fs::path& page_json) {
  const auto [w, h] = ReadTruePageSize(page_json);
  return w / h;
}

cv::Size FlatSize(const fs::path& flat) { return ReadImage(flat, cv::IMREAD_UNCHANGED).size(); }

}  // namespace

double AspectFromCorners(const Corners& corners, const Eigen::Matrix3d& K) {
  auto h = [](const Eigen::Vector2d& p) { return Eigen::Vector3d(p.x(), p.y(), 1); };
  // Zhang & He number the corners m1 = TL, m2 = TR, m3 = BL, m4 = BR.
  const Eigen::Vector3d m1 = h(corners[0]), m2 = h(corners[1]), m3 = h(corners[3]),
                        m4 = h(corners[2]);
  const double d2 = m2.cross(m4).dot(m3), d3 = m3.cross(m4).dot(m2);
  const double mean_ratio = (SideLength(corners, 0, 1) + SideLength(corners, 3, 2)) /
                            (SideLength(corners, 0, 3) + SideLength(corners, 1, 2));
  if (std::abs(d2) < 1e-12 || std::abs(d3) < 1e-12) return mean_ratio;
  const double k2 = m1.cross(m4).dot(m3) / d2, k3 = m1.cross(m4).dot(m2) / d3;
  const Eigen::Matrix3d K_inv = K.inverse();
  const Eigen::Vector3d n2 = K_inv * (k2 * m2 - m1), n3 = K_inv * (k3 * m3 - m1);
  const double aspect = n2.norm() / n3.norm();
  return std::isfinite(aspect) && aspect > 0 ? aspect : mean_ratio;
}

cv::Mat WarpByCorners(const cv::Mat& image, const Corners& corners, cv::Size size) {
  // Output pixel footprint in the image: page side length over output side.
  const double footprint =
      std::max(std::max(SideLength(corners, 0, 1), SideLength(corners, 3, 2)) / size.width,
               std::max(SideLength(corners, 0, 3), SideLength(corners, 1, 2)) / size.height);
  const int k = Supersampling(footprint);
  const double w = size.width * k, hgt = size.height * k;
  const cv::Point2f dst[4] = {{-0.5f, -0.5f},
                              {float(w - 0.5), -0.5f},
                              {float(w - 0.5), float(hgt - 0.5)},
                              {-0.5f, float(hgt - 0.5)}};
  cv::Point2f src[4];
  for (int i = 0; i < 4; ++i) src[i] = {float(corners[i].x()), float(corners[i].y())};
  const cv::Mat H = cv::getPerspectiveTransform(dst, src);  // output -> image
  cv::Mat big;
  cv::warpPerspective(image, big, H, cv::Size(int(w), int(hgt)),
                      cv::INTER_CUBIC | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
  if (k == 1) return big;
  cv::Mat out;
  cv::resize(big, out, size, 0, 0, cv::INTER_AREA);
  return out;
}

cv::Mat TextureFromTruth(const cv::Mat& photo, const PinholeCamera& camera, const PlyData& mesh,
                         cv::Size size) {
  if (!mesh.FindProperty("s") || !mesh.FindProperty("t"))
    throw InputError("true mesh has no per-vertex s, t");
  const std::vector<Triangle> triangles = Triangulate(mesh.faces);
  cv::Mat2f map = TrueMap(camera, mesh, triangles, size, 1);
  const int k = Supersampling(MapFootprint(map));
  if (k > 1) map = TrueMap(camera, mesh, triangles, size, k);
  FillHoles(map);
  cv::Mat big;
  cv::remap(photo, big, map, cv::noArray(), cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  if (k == 1) return big;
  cv::Mat out;
  cv::resize(big, out, size, 0, 0, cv::INTER_AREA);
  return out;
}

cv::Rect SeenPageRect(const std::vector<PinholeCamera>& cameras, const PlyData& mesh,
                      cv::Size size) {
  if (!mesh.FindProperty("s") || !mesh.FindProperty("t"))
    throw InputError("true mesh has no per-vertex s, t");
  const auto& s = mesh.FindProperty("s")->values;
  const auto& t = mesh.FindProperty("t")->values;
  const std::vector<Triangle> triangles = Triangulate(mesh.faces);
  std::vector<Eigen::Vector3d> screen(mesh.vertices.size());
  for (size_t i = 0; i < screen.size(); ++i)
    screen[i] = {s[i] * size.width - 0.5, t[i] * size.height - 0.5, 1.0};
  const RasterResult raster = Rasterize(screen, triangles, size.width, size.height);
  cv::Mat1b covered(size, 0), seen(size, 0);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      const int f = raster.face(y, x);
      if (f < 0) continue;
      covered(y, x) = 255;
      const double b1 = raster.bary(y, x)[0], b2 = raster.bary(y, x)[1];
      const Triangle& tri = triangles[f];
      const Eigen::Vector3d p = (1 - b1 - b2) * mesh.vertices[tri[0]] + b1 * mesh.vertices[tri[1]] +
                                b2 * mesh.vertices[tri[2]];
      for (const PinholeCamera& camera : cameras) {
        const Eigen::Vector3d xc = camera.CamFromWorld(p);
        if (xc.z() <= 0) continue;
        const Eigen::Vector2d px = camera.ProjectCam(xc);
        if (px.x() >= -0.5 && px.y() >= -0.5 && px.x() <= camera.width - 0.5 &&
            px.y() <= camera.height - 0.5) {
          seen(y, x) = 255;
          break;
        }
      }
    }
  // Only the mesh can be unseen: a side the photos see as far as the mesh
  // reaches keeps the page's edge (a mesh that stops short of s, t = 0 or 1
  // leaves pixels on no triangle, which TextureFromTruth fills).
  const cv::Rect on_mesh = cv::boundingRect(covered), r = cv::boundingRect(seen);
  if (r.empty()) return r;
  const int x0 = r.x <= on_mesh.x ? 0 : r.x, y0 = r.y <= on_mesh.y ? 0 : r.y;
  const int x1 = r.br().x >= on_mesh.br().x ? size.width : r.br().x;
  const int y1 = r.br().y >= on_mesh.br().y ? size.height : r.br().y;
  return cv::Rect(x0, y0, x1 - x0, y1 - y0);
}

FusedTexture FuseFromTruth(const std::vector<FusionView>& views, const PlyData& mesh,
                           cv::Size size) {
  if (!mesh.FindProperty("s") || !mesh.FindProperty("t"))
    throw InputError("true mesh has no per-vertex s, t");
  const auto& s = mesh.FindProperty("s")->values;
  const auto& t = mesh.FindProperty("t")->values;
  FusionSurface surface;
  surface.world = mesh.vertices;
  surface.triangles = Triangulate(mesh.faces);
  surface.width = size.width;
  surface.height = size.height;
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    surface.pixel.emplace_back(s[i] * size.width - 0.5, t[i] * size.height - 0.5);
  FusedTexture fused = FuseTexture(surface, views);
  // The paper's colour where no photo sees the page (or the mesh stops
  // short of the page's edge).
  const cv::Mat1b empty = fused.seen == 0;
  if (cv::countNonZero(fused.seen) > 0) {
    std::vector<cv::Mat> planes;
    cv::split(fused.image, planes);
    cv::Scalar paper;
    for (int c = 0; c < 3; ++c) {
      cv::Mat1b values;
      planes[c].copyTo(values);
      std::vector<double> seen;
      for (int y = 0; y < values.rows; ++y)
        for (int x = 0; x < values.cols; ++x)
          if (fused.seen(y, x) && (x + y) % 3 == 0) seen.push_back(values(y, x));
      paper[c] = Median(seen);
    }
    fused.image.setTo(paper, empty);
  }
  return fused;
}

namespace {

// The reference view warped by its four page corners (BaselineOptions).
BaselineResult Homography(const BaselineInputs& in, const BaselineOptions& options,
                          const CameraSet& cameras) {
  const fs::path gt = in.data / "ground_truth";
  std::error_code ec;
  const bool has_flat = fs::is_regular_file(gt / "flat.png", ec);
  const cv::Mat reference =
      ReadImage(MustExist(in.work / "10_sfm" / "reference.png", "run sfm first"));
  const Corners labelled = ReadCorners(
      MustExist(in.work / "20_boundary" / "boundary.json", "run segment-boundary first"));
  // Turned clockwise k times, the page's new top-left is its old corner k
  // places back (TL, TR, BR, BL order).
  const int turns = ((options.quarter_turns % 4) + 4) % 4;
  Corners corners;
  for (int i = 0; i < 4; ++i) corners[i] = labelled[(i - turns + 4) % 4];
  double aspect;
  const char* aspect_from;
  if (fs::is_regular_file(gt / "page.json", ec)) {
    aspect = PageAspect(gt / "page.json");
    aspect_from = "page.json";
  } else if (const PinholeCamera* cam = cameras.Find(cameras.reference)) {
    aspect = AspectFromCorners(corners, cam->K);
    aspect_from = "corners and K";
  } else {
    aspect = AspectFromCorners(corners, Eigen::Matrix3d::Identity());
    aspect_from = "corners";
  }
  // flat.png has the page's aspect: by default compare at exactly its size.
  cv::Size size;
  if (options.width > 0) {
    size = cv::Size(options.width, int(std::lround(options.width / aspect)));
  } else if (has_flat) {
    size = FlatSize(gt / "flat.png");
  } else {
    const int width =
        int(std::lround(0.5 * (SideLength(corners, 0, 1) + SideLength(corners, 3, 2))));
    size = cv::Size(width, int(std::lround(width / aspect)));
  }
  size = cv::Size(std::max(1, size.width), std::max(1, size.height));
  BaselineResult out;
  out.image = WarpByCorners(reference, corners, size);
  out.summary = "homography of " + cameras.reference + " by its 4 corners, " +
                std::to_string(size.width) + "x" + std::to_string(size.height) + ", aspect " +
                Fixed(aspect, 4) + " (" + aspect_from + "), " + std::to_string(turns) +
                " quarter turns";
  return out;
}

// The photo of the reference view textured through the true surface and
// camera (BaselineOptions), cropped to what the photos see if asked.
BaselineResult Oracle(const BaselineInputs& in, const BaselineOptions& options,
                      const CameraSet& cameras, const fs::path& sfm_cameras) {
  const fs::path gt = in.data / "ground_truth";
  std::error_code ec;
  if (!fs::is_regular_file(gt / "flat.png", ec))
    throw InputError((gt / "flat.png").string() + ": no such file (the oracle needs ground truth)");
  const CameraSet truth = ReadCameras(MustExist(gt / "cameras.json", "oracle"));
  const PinholeCamera* camera = truth.Find(cameras.reference);
  if (!camera)
    throw InputError((gt / "cameras.json").string() + ": no view named " + cameras.reference +
                     " (the reference of " + sfm_cameras.string() + ")");
  const fs::path photo_path = MustExist(in.data / "images" / cameras.reference, "oracle");
  const cv::Mat photo = ReadPhoto(photo_path).image;
  if (photo.cols != camera->width || photo.rows != camera->height)
    throw InputError(photo_path.string() + ": size " + std::to_string(photo.cols) + "x" +
                     std::to_string(photo.rows) + " differs from its true camera");
  const PlyData mesh = ReadPly(MustExist(gt / "mesh.ply", "oracle"));
  if (!mesh.FindProperty("s") || !mesh.FindProperty("t"))
    throw InputError((gt / "mesh.ply").string() + ": no per-vertex s, t");
  cv::Size size = FlatSize(gt / "flat.png");
  if (options.width > 0)
    size =
        cv::Size(options.width,
                 std::max(1, int(std::lround(double(options.width) * size.height / size.width))));
  BaselineResult out;
  if (options.method == Method::kOracleMultiview) {
    // The reference first, then every other photo with its true camera.
    std::vector<FusionView> views = {{*camera, {}, photo, {}, cameras.reference}};
    for (const PinholeCamera& view : truth.views) {
      if (view.image == cameras.reference) continue;
      const fs::path path = MustExist(in.data / "images" / view.image, "oracle-multiview");
      views.push_back({view, {}, ReadViewPhoto(path, view, gt / "cameras.json"), {}, view.image});
    }
    const FusedTexture fused = FuseFromTruth(views, mesh, size);
    out.image = fused.image;
    std::string shares;
    for (const FusionViewReport& v : fused.views)
      shares += (shares.empty() ? "" : ", ") + v.name + " " + Fixed(100 * v.share, 1) + " %";
    out.summary = "oracle-multiview: " + std::to_string(views.size()) +
                  " photos through the true surface and cameras (" + shares + ", unseen " +
                  Fixed(100 * fused.unseen, 1) + " %), " + std::to_string(size.width) + "x" +
                  std::to_string(size.height);
  } else {
    out.image = TextureFromTruth(photo, *camera, mesh, size);
    out.summary = "oracle: " + cameras.reference + " through the true surface and camera, " +
                  std::to_string(size.width) + "x" + std::to_string(size.height);
  }
  if (options.crop_to_seen) {
    const cv::Rect seen = SeenPageRect(truth.views, mesh, size);
    if (seen.empty())
      throw InputError((gt / "cameras.json").string() + ": no photo sees the true page");
    out.image = out.image(seen).clone();
    out.summary += ", cropped to the part the photos see: x " + std::to_string(seen.x) + ".." +
                   std::to_string(seen.x + seen.width) + ", y " + std::to_string(seen.y) + ".." +
                   std::to_string(seen.y + seen.height) + " of " + std::to_string(size.width) +
                   "x" + std::to_string(size.height);
  }
  return out;
}

}  // namespace

void DeclareOptions(OptionTable& table, BaselineOptions* o) {
  table
      .Choice("method", &o->method,
              {{"homography", Method::kHomography},
               {"oracle", Method::kOracle},
               {"oracle-multiview", Method::kOracleMultiview}},
              "the reference method")
      ->required();
  table.Value("width", &o->width, 0, std::numeric_limits<int>::max(),
              "output width in pixels, height from the page aspect (0: the size of flat.png, "
              "else the page's width in the reference view)");
  table.Value("quarter-turns", &o->quarter_turns, 0, 3,
              "homography: turn the page clockwise this many quarter turns first (bench passes "
              "60_render/render.json's orientation.quarter_turns_clockwise, so it reads the same "
              "way up as docunfold's result)");
  table.Switch("crop-to-seen", &o->crop_to_seen,
               "oracle: keep the smallest rectangle of the page that holds all of it any photo "
               "sees (ground_truth/cameras.json): the ceiling for a method that cannot know "
               "where a page cut off in every photo ends; the plain oracle where the page is "
               "seen whole");
  table.Choice("shading", &o->remove_shading, {{"keep", false}, {"remove", true}},
               "remove: divide out the light's shading afterwards, as render --shading remove "
               "does (the ceiling for such results); keep: as photographed");
}

BaselineResult Run(const BaselineInputs& in, const BaselineOptions& options) {
  if (options.crop_to_seen && options.method == Method::kHomography)
    throw UsageError("--crop-to-seen applies to the oracles only");
  const fs::path sfm_cameras = MustExist(in.work / "10_sfm" / "cameras.json", "run sfm first");
  const CameraSet cameras = ReadCameras(sfm_cameras);
  if (cameras.reference.empty())
    throw InputError(sfm_cameras.string() + ":/reference: no reference view named");
  BaselineResult out = options.method == Method::kHomography
                           ? Homography(in, options, cameras)
                           : Oracle(in, options, cameras, sfm_cameras);
  if (options.remove_shading) {
    out.image = RemoveShading(out.image).image;
    out.summary += ", shading removed";
  }
  return out;
}

}  // namespace docunfold::baseline
