#include "tests/support/truth_frame.h"

#include <opencv2/imgcodecs.hpp>
#include <random>
#include <stdexcept>

#include "common/atomic_file.h"
#include "common/json_io.h"
#include "common/raster.h"
#include "common/statistics.h"

namespace docunfold::testing {
namespace {

const PinholeCamera& FindOrThrow(const GroundTruth& gt, const std::string& image) {
  const PinholeCamera* cam = gt.cameras.Find(image);
  if (!cam) throw std::runtime_error("no true camera for " + image);
  return *cam;
}

}  // namespace

RefFromWorld ReferenceFrame(const GroundTruth& gt, const std::string& reference) {
  const PinholeCamera& cam = FindOrThrow(gt, reference);
  RasterResult raster = RasterizeMesh(cam, gt.mesh.vertices, gt.triangles);
  std::vector<double> depths;
  for (const Eigen::Vector3d& v : gt.mesh.vertices) {
    const Eigen::Vector3d xc = cam.CamFromWorld(v);
    if (xc.z() <= 0) continue;
    const Eigen::Vector2d px = cam.ProjectCam(xc);
    const int x = int(std::lround(px.x())), y = int(std::lround(px.y()));
    if (x < 0 || y < 0 || x >= cam.width || y >= cam.height) continue;
    if (xc.z() > raster.depth(y, x) * (1 + 2e-3)) continue;
    depths.push_back(xc.z());
  }
  if (depths.empty()) throw std::runtime_error(reference + " sees no part of the page");
  RefFromWorld f;
  f.scale = 1.0 / Median(std::move(depths));
  f.R = cam.R;
  f.t = cam.t;
  return f;
}

CameraSet CamerasInReferenceFrame(const GroundTruth& gt, const std::string& reference) {
  const RefFromWorld ref = ReferenceFrame(gt, reference);
  CameraSet out;
  out.reference = reference;
  for (const PinholeCamera& c : gt.cameras.views) {
    // x_cam = R_c x_w + t_c and x_w = R^T (x_ref / s - t), so in the scaled
    // frame x_cam * s = R_c R^T x_ref + s (t_c - R_c R^T t).
    PinholeCamera k = c;
    k.R = c.R * ref.R.transpose();
    k.t = ref.scale * (c.t - k.R * ref.t);
    out.views.push_back(k);
  }
  return out;
}

TrueMeshes TrueMeshesInReferenceFrame(const GroundTruth& gt, const std::string& reference) {
  const RefFromWorld ref = ReferenceFrame(gt, reference);
  TrueMeshes m;
  const auto& s = gt.mesh.FindProperty("s")->values;
  const auto& t = gt.mesh.FindProperty("t")->values;
  for (size_t i = 0; i < gt.mesh.vertices.size(); ++i) {
    m.mesh3d.vertices.push_back(ref(gt.mesh.vertices[i]));
    m.mesh2d.vertices.push_back(Eigen::Vector3d(s[i] * gt.width_m, t[i] * gt.height_m, 0) *
                                ref.scale);
  }
  m.mesh3d.faces = m.mesh2d.faces = gt.mesh.faces;
  if (auto grid = gt.mesh.GridSize()) {
    m.mesh3d.SetGridSize((*grid)[0], (*grid)[1]);
    m.mesh2d.SetGridSize((*grid)[0], (*grid)[1]);
  }
  return m;
}

void WriteSfmFromTruth(const GroundTruth& gt, const std::string& reference, const fs::path& out_dir,
                       const SfmFromTruthOptions& options) {
  const RefFromWorld ref = ReferenceFrame(gt, reference);
  const CameraSet cameras = CamerasInReferenceFrame(gt, reference);
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> uni(0, 1);
  const double sigma = options.noise * gt.Diagonal() * ref.scale;
  std::normal_distribution<double> gauss(0, sigma > 0 ? sigma : 1);

  std::vector<RasterResult> rasters;
  for (const PinholeCamera& c : gt.cameras.views)
    rasters.push_back(RasterizeMesh(c, gt.mesh.vertices, gt.triangles));
  auto views_seeing = [&](const Eigen::Vector3d& x) {
    int n = 0;
    for (size_t v = 0; v < gt.cameras.views.size(); ++v) {
      const PinholeCamera& c = gt.cameras.views[v];
      const Eigen::Vector3d xc = c.CamFromWorld(x);
      if (xc.z() <= 0) continue;
      const Eigen::Vector2d px = c.ProjectCam(xc);
      const int u = int(std::lround(px.x())), w = int(std::lround(px.y()));
      if (u < 0 || w < 0 || u >= c.width || w >= c.height) continue;
      if (xc.z() <= rasters[v].depth(w, u) * (1 + 2e-3)) ++n;
    }
    return n;
  };

  PlyData points;
  std::vector<double> track, error;
  for (int tries = 0;
       int(points.vertices.size()) < options.num_points && tries < options.num_points * 50;
       ++tries) {
    auto p = gt.SurfacePoint({uni(rng) * (gt.flat_width - 1), uni(rng) * (gt.flat_height - 1)});
    if (!p) continue;
    const int n = views_seeing(*p);
    if (n < 2) continue;
    Eigen::Vector3d x = ref(*p);
    if (sigma > 0) x += Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    points.vertices.push_back(x);
    track.push_back(n);
    error.push_back(0.5);
  }
  if (options.outlier_fraction > 0 && !points.vertices.empty()) {
    Eigen::Vector3d lo = points.vertices[0], hi = lo;
    for (const auto& v : points.vertices) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    const int n = int(options.outlier_fraction * points.vertices.size());
    for (int i = 0; i < n; ++i) {
      points.vertices.push_back(
          lo + (hi - lo).cwiseProduct(Eigen::Vector3d(uni(rng), uni(rng), uni(rng))));
      track.push_back(2);
      error.push_back(2.0);
    }
  }
  points.colors.assign(points.vertices.size(), {128, 128, 128});
  points.SetProperty("track_length", track, PlyScalar::kUint32);
  points.SetProperty("reprojection_error", error);
  points.comments.push_back("sfm points from ground truth (tests/support/truth_frame)");

  EnsureDirectory(out_dir);
  Json doc = MakeHeader("docunfold.cameras", 1, "sfm-from-truth");
  doc["reference"] = reference;
  doc["views"] = Json::array();
  for (const PinholeCamera& c : cameras.views) doc["views"].push_back(CameraToJson(c));
  WriteJsonAtomic(out_dir / "cameras.json", doc);
  WritePly(out_dir / "points.ply", points);
  cv::Mat image = ReadImage(gt.root / "images" / reference);
  WriteImageAtomic(out_dir / "reference.png", image);
}

}  // namespace docunfold::testing
