// Inputs of init-mesh made without the real sfm and segment-boundary: from
// a data set's ground truth (10_sfm by WriteSfmFromTruth, 20_boundary from
// the true page outline in the reference view), or from an analytic curled
// sheet in front of a camera (no data needed).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/atomic_file.h"
#include "common/camera.h"
#include "common/grid_mesh.h"
#include "common/json_io.h"
#include "common/ply.h"
#include "common/point_source.h"
#include "common/raster.h"
#include "tests/isometry/test_meshes.h"
#include "tests/support/ground_truth.h"
#include "tests/support/look_at.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {

// boundary.json + mask.png from four side polylines in the image.
inline void WriteBoundary(const fs::path& dir, const std::string& image, int width, int height,
                          const std::array<std::vector<Eigen::Vector2d>, 4>& sides,
                          const cv::Mat1b& mask) {
  // A side is real unless it runs along the image border somewhere.
  auto inside = [&](const std::vector<Eigen::Vector2d>& s) {
    for (const auto& p : s)
      if (p.x() < 0.5 || p.y() < 0.5 || p.x() > width - 1.5 || p.y() > height - 1.5) return false;
    return true;
  };
  auto to_json = [](const std::vector<Eigen::Vector2d>& s) {
    Json a = Json::array();
    for (const auto& p : s) a.push_back({p.x(), p.y()});
    return a;
  };
  Json doc = MakeHeader("docunfold.boundary", 1, "truth-boundary");
  doc["image"] = image;
  doc["width"] = width;
  doc["height"] = height;
  std::vector<Eigen::Vector2d> contour = sides[0];
  contour.insert(contour.end(), sides[1].begin() + 1, sides[1].end());
  contour.insert(contour.end(), sides[2].rbegin() + 1, sides[2].rend());
  contour.insert(contour.end(), sides[3].rbegin() + 1, sides[3].rend() - 1);
  doc["contour"] = to_json(contour);
  doc["corners"] = to_json({sides[0].front(), sides[0].back(), sides[2].back(), sides[2].front()});
  const char* names[4] = {"top", "right", "bottom", "left"};
  for (int s = 0; s < 4; ++s)
    doc["sides"][names[s]] = {{"points", to_json(sides[s])}, {"real", inside(sides[s])}};
  EnsureDirectory(dir);
  WriteJsonAtomic(dir / "boundary.json", doc);
  WriteImageAtomic(dir / "mask.png", mask);
}

// The true page border in a view: vertices of the true mesh with s or t at
// 0 or 1, projected; sides top (t = 0, s up), right (s = 1, t up), bottom
// (t = 1, s up), left (s = 0, t up), as boundary.json orders them.
inline std::array<std::vector<Eigen::Vector2d>, 4> TrueSides(const GroundTruth& gt,
                                                             const PinholeCamera& cam) {
  const auto& s = gt.mesh.FindProperty("s")->values;
  const auto& t = gt.mesh.FindProperty("t")->values;
  std::array<std::vector<std::pair<double, Eigen::Vector2d>>, 4> raw;
  const double eps = 1e-4;
  for (size_t i = 0; i < gt.mesh.vertices.size(); ++i) {
    const Eigen::Vector2d px = cam.Project(gt.mesh.vertices[i]);
    if (t[i] < eps) raw[0].push_back({s[i], px});
    if (s[i] > 1 - eps) raw[1].push_back({t[i], px});
    if (t[i] > 1 - eps) raw[2].push_back({s[i], px});
    if (s[i] < eps) raw[3].push_back({t[i], px});
  }
  // Where the page leaves the image, the visible outline runs along the
  // image border (as segment-boundary sees it): clamp to the image.
  auto clamp = [&](Eigen::Vector2d p) {
    return Eigen::Vector2d(std::clamp(p.x(), 0.0, cam.width - 1.0),
                           std::clamp(p.y(), 0.0, cam.height - 1.0));
  };
  std::array<std::vector<Eigen::Vector2d>, 4> sides;
  for (int k = 0; k < 4; ++k) {
    std::sort(raw[k].begin(), raw[k].end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (size_t i = 0; i < raw[k].size(); i += 2) sides[k].push_back(clamp(raw[k][i].second));
    if ((raw[k].size() - 1) % 2) sides[k].push_back(clamp(raw[k].back().second));
  }
  return sides;
}

// 10_sfm and 20_boundary of a data set from its truth, for `reference`.
inline void WriteWorkFromTruth(const GroundTruth& gt, const std::string& reference,
                               const fs::path& work, const SfmFromTruthOptions& sfm) {
  WriteSfmFromTruth(gt, reference, work / "10_sfm", sfm);
  const PinholeCamera& cam = *gt.cameras.Find(reference);
  WriteBoundary(work / "20_boundary", "reference.png", cam.width, cam.height, TrueSides(gt, cam),
                TruePageMask(gt, cam));
}

// An analytic scene: a curled sheet (0.21 x 0.297, curl radius 0.2) seen by
// a 640x480 camera at the world origin, `points` SfM points on it (those
// with flat x below `keep_left_fraction` of the width only, to make pages
// with missing parts), 10_sfm and 20_boundary written to `work`. Returns the
// true pair.
// `sheet` (around z = 1, long side down the image) brought nearer, turned so
// its long side runs across the image, `points` SfM points on it (those
// whose flat position `keep` accepts), 10_sfm and 20_boundary written to
// `work`. Returns the pair as placed.
template <class Keep>
MeshPair WriteSheetWork(const fs::path& work, MeshPair sheet, int points, const Keep& keep) {
  for (auto& v : sheet.mesh3d) v.z() = 0.45 + 0.45 * (v.z() - 1.0) + 0.0;  // nearer camera
  PinholeCamera cam;
  cam.image = "ref.jpg";
  cam.width = 640;
  cam.height = 480;
  cam.K << 900, 0, 319.5, 0, 900, 239.5, 0, 0, 1;
  // Turn the sheet so its long side runs across the image.
  for (auto& v : sheet.mesh3d) {
    const double x = v.x(), y = v.y();
    v.x() = y;
    v.y() = -x;
  }
  const SampledPoints sample = SampleSurface(sheet, points, 0.0005, 0.0, 3);
  PlyData cloud;
  for (const auto& p : sample.points) {
    // Keep points by their flat position: nearest vertex's M' x.
    double best = 1e9;
    int vi = 0;
    for (size_t i = 0; i < sheet.mesh3d.size(); ++i)
      if ((sheet.mesh3d[i] - p).norm() < best) {
        best = (sheet.mesh3d[i] - p).norm();
        vi = int(i);
      }
    if (keep(sheet.mesh2d[vi])) cloud.vertices.push_back(p);
  }
  cloud.colors.assign(cloud.vertices.size(), {100, 100, 100});
  EnsureDirectory(work / "10_sfm");
  WritePly(work / "10_sfm/points.ply", cloud);
  Json doc = MakeHeader("docunfold.cameras", 1, "synthetic");
  doc["reference"] = cam.image;
  doc["views"] = Json::array({CameraToJson(cam)});
  WriteJsonAtomic(work / "10_sfm/cameras.json", doc);
  WriteImageAtomic(work / "10_sfm/reference.png",
                   cv::Mat(cam.height, cam.width, CV_8UC3, cv::Scalar(90, 120, 90)));
  // Sides from the border of the grid: top = row 0 (flat y = 0), etc.
  std::array<std::vector<Eigen::Vector2d>, 4> sides;
  const QuadGrid& g = sheet.grid;
  for (int c = 0; c < g.nx; ++c) sides[0].push_back(cam.Project(sheet.mesh3d[g.Index(0, c)]));
  for (int r = 0; r < g.ny; ++r)
    sides[1].push_back(cam.Project(sheet.mesh3d[g.Index(r, g.nx - 1)]));
  for (int c = 0; c < g.nx; ++c)
    sides[2].push_back(cam.Project(sheet.mesh3d[g.Index(g.ny - 1, c)]));
  for (int r = 0; r < g.ny; ++r) sides[3].push_back(cam.Project(sheet.mesh3d[g.Index(r, 0)]));
  const RasterResult raster = RasterizeMesh(cam, sheet.mesh3d, g.Triangles());
  cv::Mat1b mask = raster.face >= 0;
  WriteBoundary(work / "20_boundary", "reference.png", cam.width, cam.height, sides, mask);
  return sheet;
}

inline MeshPair WriteSyntheticWork(const fs::path& work, int points = 1500,
                                   double keep_left_fraction = 1.0) {
  return WriteSheetWork(
      work, CurledSheet(22, 30, 0.21, 0.297, 0.2), points,
      [&](const Eigen::Vector2d& flat) { return flat.x() <= keep_left_fraction * 0.21; });
}

// A page folded by `fold_deg` down its middle and tilted by `tilt_deg` about
// the fold's normal direction, with points only inside a text block that
// leaves `margin` (fraction of each side) blank all round, as printed pages do.
inline MeshPair WriteFoldedPageWithMarginsWork(const fs::path& work, double fold_deg,
                                               double tilt_deg, double margin) {
  const int nx = 22, ny = 30;
  const double w = 0.21, h = 0.297;
  MeshPair sheet = ProfileSheet(
      nx, ny, w, h, [&](int c) { return c == nx / 2 - 1 ? fold_deg * M_PI / 180 : 0.0; });
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(tilt_deg * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Vector3d centre(0, 0, 1);
  for (auto& v : sheet.mesh3d) v = centre + tilt * (v - centre);
  return WriteSheetWork(work, sheet, 2500, [&](const Eigen::Vector2d& flat) {
    return flat.x() >= margin * w && flat.x() <= (1 - margin) * w && flat.y() >= margin * h &&
           flat.y() <= (1 - margin) * h;
  });
}

// A sheet folded twice along lines from its top side to its bottom side (a
// zig-zag, like a receipt), tilted, with points only in strips along the top
// and bottom sides (`strip` of the height each: rows of print) and none in the
// blank band between, plus densify-like outline points (PointSource::kOutline) along all
// four sides; points.ply carries `source` (0 for the strips' points).
inline MeshPair WriteZigZagWithBlankBandWork(const fs::path& work, double fold_deg, double strip) {
  const int nx = 31, ny = 30;
  const double w = 0.21, h = 0.297;
  MeshPair sheet = ProfileSheet(nx, ny, w, h, [&](int c) {
    return c == 9 ? fold_deg * M_PI / 180 : c == 19 ? -fold_deg * M_PI / 180 : 0.0;
  });
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(25 * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Vector3d centre(0, 0, 1);
  for (auto& v : sheet.mesh3d) v = centre + tilt * (v - centre);
  const MeshPair placed = WriteSheetWork(work, sheet, 3000, [&](const Eigen::Vector2d& flat) {
    return flat.y() <= strip * h || flat.y() >= (1 - strip) * h;
  });
  PlyData cloud = ReadPly(work / "10_sfm/points.ply");
  PlyProperty source{"source", PlyScalar::kUint8, std::vector<double>(cloud.vertices.size(), 0)};
  const QuadGrid& g = placed.grid;
  auto along = [&](int r0, int c0, int r1, int c1) {  // border vertex to vertex
    const Eigen::Vector3d a = placed.mesh3d[g.Index(r0, c0)], b = placed.mesh3d[g.Index(r1, c1)];
    for (int k = 0; k < 8; ++k) {
      cloud.vertices.push_back(a + (b - a) * (k / 8.0));
      cloud.colors.push_back({250, 250, 250});
      source.values.push_back(double(PointSource::kOutline));
    }
  };
  for (int c = 0; c + 1 < g.nx; ++c) {
    along(0, c, 0, c + 1);
    along(g.ny - 1, c, g.ny - 1, c + 1);
  }
  for (int r = 0; r + 1 < g.ny; ++r) {
    along(r, 0, r + 1, 0);
    along(r, g.nx - 1, r + 1, g.nx - 1);
  }
  cloud.properties.push_back(source);
  WritePly(work / "10_sfm/points.ply", cloud);
  return placed;
}

// 10_sfm (`points`, the cameras `cams`, the first of them the reference, and
// a plain reference.png) and 20_boundary (the reference outline `sides`, the
// page masks of `truth` in every camera) of a scene.
inline void WriteMultiViewWork(const fs::path& work, const MeshPair& truth,
                               const std::vector<PinholeCamera>& cams,
                               const std::vector<Eigen::Vector3d>& points,
                               const std::array<std::vector<Eigen::Vector2d>, 4>& sides) {
  const PinholeCamera& ref = cams[0];
  PlyData cloud;
  cloud.vertices = points;
  cloud.colors.assign(cloud.vertices.size(), {100, 100, 100});
  EnsureDirectory(work / "10_sfm");
  WritePly(work / "10_sfm/points.ply", cloud);
  Json doc = MakeHeader("docunfold.cameras", 1, "synthetic");
  doc["reference"] = ref.image;
  doc["views"] = Json::array();
  for (const auto& cam : cams) doc["views"].push_back(CameraToJson(cam));
  WriteJsonAtomic(work / "10_sfm/cameras.json", doc);
  WriteImageAtomic(work / "10_sfm/reference.png",
                   cv::Mat(ref.height, ref.width, CV_8UC3, cv::Scalar(90, 120, 90)));
  auto mask_in = [&](const PinholeCamera& cam) {
    const RasterResult raster = RasterizeMesh(cam, truth.mesh3d, truth.grid.Triangles());
    return cv::Mat1b(raster.face >= 0);
  };
  WriteBoundary(work / "20_boundary", "reference.png", ref.width, ref.height, sides, mask_in(ref));
  for (size_t v = 1; v < cams.size(); ++v) {
    const fs::path dir = work / "20_boundary/views" / fs::path(cams[v].image).stem();
    EnsureDirectory(dir);
    WriteImageAtomic(dir / "mask.png", mask_in(cams[v]));
  }
}

// A page (0.21 x 0.297) folded along its diagonal from the top-right to the
// bottom-left corner: the top-left triangle lies flat, facing the reference
// camera 0.45 away; the other stands at 90 degrees toward that camera, which
// sees it edge-on, so the reference outline is a triangle. Two more photos
// see both halves; their page masks go to 20_boundary/views/. SfM points
// cover the whole page. Returns the true pair.
inline MeshPair WriteDiagonalFoldWork(const fs::path& work) {
  const double w = 0.21, h = 0.297, d = 0.45;
  const int nx = 43, ny = 61;
  const Eigen::Vector2d c1(w / 2, -h / 2), c3(-w / 2, h / 2);  // the fold's ends
  const Eigen::Vector2d along = (c3 - c1).normalized();
  const Eigen::Vector2d across(along.y(), -along.x());  // toward the standing half
  MeshPair truth;
  truth.grid.nx = nx;
  truth.grid.ny = ny;
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      const Eigen::Vector2d flat(w * c / (nx - 1), h * r / (ny - 1));
      const Eigen::Vector2d p = flat - Eigen::Vector2d(w / 2, h / 2);
      const double height = std::max(0.0, across.dot(p - c1));  // past the fold: standing
      const Eigen::Vector2d on_plane = p - height * across;
      truth.mesh2d.push_back(flat);
      truth.mesh3d.push_back({on_plane.x(), on_plane.y(), d - height});
    }
  if (across.dot(Eigen::Vector2d(w / 2, h / 2) - c1) < 0)
    throw std::logic_error("the standing half must hold the bottom-right corner");
  std::vector<PinholeCamera> cams = {
      LookAtCamera("ref.jpg", {0, 0, 0}, {0, 0, d}, 640, 480, 600),
      LookAtCamera("side_a.jpg", {0.3, 0.25, 0.05}, {0, 0, d - 0.05}, 640, 480, 600),
      LookAtCamera("side_b.jpg", {0.25, 0.3, 0.1}, {0, 0, d - 0.05}, 640, 480, 600)};
  const PinholeCamera& ref = cams[0];
  // The reference outline: the flat triangle, as four sides (its long side
  // split at the middle, as segment-boundary splits an outline with three
  // corners).
  auto segment = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    std::vector<Eigen::Vector2d> s;
    for (int k = 0; k <= 20; ++k) {
      const Eigen::Vector2d p = a + (b - a) * (k / 20.0);
      s.push_back(ref.Project({p.x(), p.y(), d}));
    }
    return s;
  };
  const Eigen::Vector2d c0(-w / 2, -h / 2), middle = (c1 + c3) / 2;
  WriteMultiViewWork(work, truth, cams, SampleSurface(truth, 3000, 0.0003, 0.0, 7).points,
                     {segment(c0, c1), segment(c1, middle), segment(c3, middle), segment(c0, c3)});
  return truth;
}

// A receipt (0.08 x 0.2) lying flat 0.45 from the reference camera, its last
// `flap` of the length folded up by `fold_deg` towards the camera, which
// looks at it from beyond the top end, so it sees the printed side of the
// flap at a grazing angle. SfM points lie on the flat part only (the flap is
// blank paper, or seen from behind by the other photos); two more photos see
// the flap from the side and from beyond the bottom end. The reference
// outline is the true border. Returns the true pair.
inline MeshPair WriteStandingEndWork(const fs::path& work, double fold_deg, double flap = 0.2) {
  const double w = 0.08, h = 0.2, d = 0.45, hinge = h * (1 - flap);
  const double angle = fold_deg * 3.14159265358979323846 / 180;
  MeshPair truth;
  truth.grid.nx = 17;
  truth.grid.ny = 41;
  for (int r = 0; r < truth.grid.ny; ++r)
    for (int c = 0; c < truth.grid.nx; ++c) {
      const Eigen::Vector2d flat(w * c / (truth.grid.nx - 1), h * r / (truth.grid.ny - 1));
      const double x = flat.x() - w / 2, past = std::max(0.0, flat.y() - hinge);
      const double y = std::min(flat.y(), hinge) + past * std::cos(angle) - h / 2;
      truth.mesh2d.push_back(flat);
      truth.mesh3d.push_back({x, y, d - past * std::sin(angle)});
    }
  std::vector<PinholeCamera> cams = {
      LookAtCamera("ref.jpg", {0, -0.25, 0.05}, {0, 0.02, d}, 640, 480, 700),
      LookAtCamera("side.jpg", {0.3, 0.05, 0.1}, {0, 0.05, d - 0.03}, 640, 480, 700),
      LookAtCamera("beyond.jpg", {0.05, 0.35, 0.1}, {0, 0.03, d - 0.03}, 640, 480, 700)};
  std::vector<Eigen::Vector3d> points;
  for (const Eigen::Vector3d& p : SampleSurface(truth, 3000, 0.0002, 0.0, 11).points)
    if (p.y() < hinge - h / 2 - 0.005) points.push_back(p);
  std::array<std::vector<Eigen::Vector2d>, 4> sides;
  const QuadGrid& g = truth.grid;
  for (int c = 0; c < g.nx; ++c) {
    sides[0].push_back(cams[0].Project(truth.mesh3d[size_t(g.Index(0, c))]));
    sides[2].push_back(cams[0].Project(truth.mesh3d[size_t(g.Index(g.ny - 1, c))]));
  }
  for (int r = 0; r < g.ny; ++r) {
    sides[1].push_back(cams[0].Project(truth.mesh3d[size_t(g.Index(r, g.nx - 1))]));
    sides[3].push_back(cams[0].Project(truth.mesh3d[size_t(g.Index(r, 0))]));
  }
  WriteMultiViewWork(work, truth, cams, points, sides);
  return truth;
}

// The command line pipeline.mk uses, on a work folder.
inline std::string InitMeshCommand(const fs::path& work, const std::string& extra = "") {
  return Quote(StageBinary("init-mesh").string()) + " --sfm " + Quote((work / "10_sfm").string()) +
         " --boundary " + Quote((work / "20_boundary").string()) + " --out " +
         Quote((work / "40_init").string()) + " " + extra + " 2>&1";
}

}  // namespace docunfold::testing
