#include "tests/support/ground_truth.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "common/json_io.h"

namespace docunfold::testing {

std::optional<GroundTruth> LoadGroundTruth(const fs::path& dataset) {
  GroundTruth gt;
  gt.root = dataset;
  const fs::path dir = dataset / "ground_truth";
  try {
    Json page = ReadJsonFile(dir / "page.json");
    gt.width_m = page.at("width_m").get<double>();
    gt.height_m = page.at("height_m").get<double>();
    gt.cameras = ReadCameras(dir / "cameras.json");
    gt.mesh = ReadPly(dir / "mesh.ply");
    gt.triangles = Triangulate(gt.mesh.faces);
    cv::Mat flat = cv::imread((dir / "flat.png").string(), cv::IMREAD_UNCHANGED);
    if (flat.empty()) throw std::runtime_error("cannot read flat.png");
    gt.flat_width = flat.cols;
    gt.flat_height = flat.rows;
    if (!gt.mesh.FindProperty("s") || !gt.mesh.FindProperty("t"))
      throw std::runtime_error("mesh.ply lacks s, t");
    if (fs::exists(dir / "features.json")) {
      Json f = ReadJsonFile(dir / "features.json");
      for (const Json& l : f.at("lines")) {
        TrueLine line;
        line.kind = l.at("kind").get<std::string>();
        for (const Json& p : l.at("points"))
          line.points.emplace_back(p.at(0).get<double>(), p.at(1).get<double>());
        gt.lines.push_back(std::move(line));
      }
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << dataset << ": ground truth: " << e.what();
    return std::nullopt;
  }
  return gt;
}

std::optional<Eigen::Vector3d> GroundTruth::SurfacePoint(
    const Eigen::Vector2d& flat_px) const {
  if (st_scale_ == 0) {
    // Rasterize the mesh in flat.png pixel space once; depth is irrelevant.
    st_scale_ = 1.0;
    const auto& s = mesh.FindProperty("s")->values;
    const auto& t = mesh.FindProperty("t")->values;
    std::vector<Eigen::Vector3d> screen(mesh.vertices.size());
    for (size_t i = 0; i < screen.size(); ++i)
      screen[i] = {s[i] * flat_width - 0.5, t[i] * flat_height - 0.5, 1.0};
    st_raster_ = Rasterize(screen, triangles, flat_width, flat_height);
  }
  const int x = int(std::lround(flat_px.x())), y = int(std::lround(flat_px.y()));
  // Points on the page border round to the nearest covered pixel.
  const int cx = std::clamp(x, 0, flat_width - 1), cy = std::clamp(y, 0, flat_height - 1);
  if (std::abs(cx - flat_px.x()) > 1.5 || std::abs(cy - flat_px.y()) > 1.5) return std::nullopt;
  const int f = st_raster_.face(cy, cx);
  if (f < 0) return std::nullopt;
  // Exact barycentrics of flat_px in the face's (s, t) triangle.
  const auto& s = mesh.FindProperty("s")->values;
  const auto& t = mesh.FindProperty("t")->values;
  const Triangle& tri = triangles[f];
  Eigen::Vector2d a(s[tri[0]] * flat_width - 0.5, t[tri[0]] * flat_height - 0.5);
  Eigen::Vector2d b(s[tri[1]] * flat_width - 0.5, t[tri[1]] * flat_height - 0.5);
  Eigen::Vector2d c(s[tri[2]] * flat_width - 0.5, t[tri[2]] * flat_height - 0.5);
  Eigen::Matrix2d m;
  m << b - a, c - a;
  Eigen::Vector2d l = m.inverse() * (flat_px - a);
  return (1 - l.x() - l.y()) * mesh.vertices[tri[0]] + l.x() * mesh.vertices[tri[1]] +
         l.y() * mesh.vertices[tri[2]];
}

cv::Mat1b TruePageMask(const GroundTruth& gt, const PinholeCamera& camera) {
  RasterResult r = RasterizeMesh(camera, gt.mesh.vertices, gt.triangles);
  return r.face >= 0;
}

std::array<Eigen::Vector2d, 4> TrueCorners(const GroundTruth& gt,
                                           const PinholeCamera& camera) {
  // The mesh vertex nearest to each corner of the (s, t) square: grids of
  // ground truth include the corners themselves.
  const Eigen::Vector2d st[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const auto& s = gt.mesh.FindProperty("s")->values;
  const auto& t = gt.mesh.FindProperty("t")->values;
  std::array<Eigen::Vector2d, 4> out;
  for (int i = 0; i < 4; ++i) {
    size_t best = 0;
    double best_d = 1e300;
    for (size_t v = 0; v < s.size(); ++v) {
      const double d = (Eigen::Vector2d(s[v], t[v]) - st[i]).squaredNorm();
      if (d < best_d) { best_d = d; best = v; }
    }
    out[i] = camera.Project(gt.mesh.vertices[best]);
  }
  return out;
}

std::vector<TrueLine> TrueLinesInView(const GroundTruth& gt,
                                      const PinholeCamera& camera,
                                      double step_px) {
  RasterResult depth = RasterizeMesh(camera, gt.mesh.vertices, gt.triangles);
  std::vector<TrueLine> out;
  for (const TrueLine& line : gt.lines) {
    TrueLine piece{line.kind, {}};
    auto flush = [&] {
      if (piece.points.size() >= 2) out.push_back(piece);
      piece.points.clear();
    };
    for (size_t k = 0; k + 1 < line.points.size(); ++k) {
      const Eigen::Vector2d a = line.points[k], b = line.points[k + 1];
      const int n = std::max(1, int(std::ceil((b - a).norm() / step_px)));
      for (int j = 0; j <= n; ++j) {
        if (k > 0 && j == 0) continue;
        auto p3 = gt.SurfacePoint(a + (b - a) * (double(j) / n));
        bool visible = false;
        Eigen::Vector2d px;
        if (p3) {
          Eigen::Vector3d xc = camera.CamFromWorld(*p3);
          px = camera.ProjectCam(xc);
          const int x = int(std::lround(px.x())), y = int(std::lround(px.y()));
          visible = xc.z() > 0 && x >= 0 && y >= 0 && x < camera.width &&
                    y < camera.height &&
                    xc.z() <= depth.depth(y, x) * (1 + 2e-3);
        }
        if (visible) piece.points.push_back(px); else flush();
      }
    }
    flush();
  }
  return out;
}

}  // namespace docunfold::testing
