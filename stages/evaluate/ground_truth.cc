#include "stages/evaluate/ground_truth.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "common/errors.h"
#include "common/json_io.h"

namespace docunfold::evaluate {

bool HasTrueSurface(const fs::path& dataset) {
  std::error_code ec;
  for (const char* f : {"page.json", "cameras.json", "mesh.ply", "flat.png"})
    if (!fs::is_regular_file(dataset / "ground_truth" / f, ec)) return false;
  return true;
}

GroundTruth LoadGroundTruth(const fs::path& dataset) {
  GroundTruth gt;
  gt.root = dataset;
  const fs::path dir = dataset / "ground_truth";
  Json page = ReadJsonFile(dir / "page.json");
  JsonReader page_reader(page, dir / "page.json");
  gt.width_m = page_reader.Number("/width_m");
  gt.height_m = page_reader.Number("/height_m");
  gt.cameras = ReadCameras(dir / "cameras.json");
  gt.mesh = ReadPly(dir / "mesh.ply");
  gt.triangles = Triangulate(gt.mesh.faces);
  const fs::path flat_path = dir / "flat.png";
  cv::Mat flat = cv::imread(flat_path.string(), cv::IMREAD_UNCHANGED);
  if (flat.empty()) throw InputError(flat_path.string() + ": missing or not an image");
  gt.flat_width = flat.cols;
  gt.flat_height = flat.rows;
  if (!gt.mesh.FindProperty("s") || !gt.mesh.FindProperty("t"))
    throw InputError((dir / "mesh.ply").string() + ": no per-vertex s and t");
  const fs::path features = dir / "features.json";
  if (fs::exists(features)) {
    Json f = ReadJsonFile(features);
    JsonReader r(f, features);
    const Json& lines = r.At("/lines");
    if (!lines.is_array()) r.Fail("/lines", "expected an array");
    for (size_t i = 0; i < lines.size(); ++i) {
      const std::string p = "/lines/" + std::to_string(i);
      TrueLine line;
      line.kind = r.String(p + "/kind");
      line.points = r.Points(p + "/points", 2);
      gt.lines.push_back(std::move(line));
    }
  }
  return gt;
}

std::optional<Eigen::Vector3d> GroundTruth::SurfacePoint(const Eigen::Vector2d& flat_px) const {
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

const RasterResult& GroundTruth::ViewRaster(const PinholeCamera& camera) const {
  const bool same = view_camera_ && view_camera_->width == camera.width &&
                    view_camera_->height == camera.height && view_camera_->K == camera.K &&
                    view_camera_->R == camera.R && view_camera_->t == camera.t;
  if (!same) {
    view_raster_ = RasterizeMesh(camera, mesh.vertices, triangles);
    view_camera_ = camera;
  }
  return view_raster_;
}

namespace {

// Whether the surface point p3 is seen by `camera` (in front of it, inside
// its image and not behind the page itself), and where.
bool SeenAt(const RasterResult& depth, const PinholeCamera& camera,
            const std::optional<Eigen::Vector3d>& p3, Eigen::Vector2d* px) {
  if (!p3) return false;
  const Eigen::Vector3d xc = camera.CamFromWorld(*p3);
  *px = camera.ProjectCam(xc);
  const int x = int(std::lround(px->x())), y = int(std::lround(px->y()));
  return xc.z() > 0 && x >= 0 && y >= 0 && x < camera.width && y < camera.height &&
         xc.z() <= depth.depth(y, x) * (1 + 2e-3);
}

// Whether `camera` sees the printed side of the page at flat pixel q: the
// map from flat.png into the image keeps its orientation there. Where it
// turns it over (a corner curled over the page), the camera sees the
// blank back, and the print on the other side is no line it could find.
bool PrintedSideSeen(const GroundTruth& gt, const PinholeCamera& camera, const Eigen::Vector2d& q) {
  const double e = 1.0;  // flat pixels
  const double sx = q.x() + e < gt.flat_width - 1 ? e : -e;
  const double sy = q.y() + e < gt.flat_height - 1 ? e : -e;
  const auto p0 = gt.SurfacePoint(q), p1 = gt.SurfacePoint(q + Eigen::Vector2d(sx, 0)),
             p2 = gt.SurfacePoint(q + Eigen::Vector2d(0, sy));
  if (!p0 || !p1 || !p2) return true;
  const Eigen::Vector2d i0 = camera.ProjectCam(camera.CamFromWorld(*p0));
  const Eigen::Vector2d u = camera.ProjectCam(camera.CamFromWorld(*p1)) - i0;
  const Eigen::Vector2d v = camera.ProjectCam(camera.CamFromWorld(*p2)) - i0;
  return (u.x() * v.y() - u.y() * v.x()) * sx * sy > 0;
}

// Whether the print at flat pixel q is seen by `camera` (SeenAt on the
// printed side; `depth` is the page rasterized in it), and where.
bool PrintSeenAt(const GroundTruth& gt, const RasterResult& depth, const PinholeCamera& camera,
                 const Eigen::Vector2d& q, Eigen::Vector2d* px) {
  return SeenAt(depth, camera, gt.SurfacePoint(q), px) && PrintedSideSeen(gt, camera, q);
}

}  // namespace

bool TruePointSeen(const GroundTruth& gt, const PinholeCamera& camera,
                   const Eigen::Vector2d& flat_px) {
  Eigen::Vector2d px;
  return PrintSeenAt(gt, gt.ViewRaster(camera), camera, flat_px, &px);
}

cv::Mat1b TruePageMask(const GroundTruth& gt, const PinholeCamera& camera) {
  return gt.ViewRaster(camera).face >= 0;
}

std::array<Eigen::Vector2d, 4> TrueCorners(const GroundTruth& gt, const PinholeCamera& camera) {
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
      if (d < best_d) {
        best_d = d;
        best = v;
      }
    }
    out[i] = camera.Project(gt.mesh.vertices[best]);
  }
  return out;
}

std::vector<TrueLine> TrueLinesInView(const GroundTruth& gt, const PinholeCamera& camera,
                                      double step_px) {
  const RasterResult& depth = gt.ViewRaster(camera);
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
        const Eigen::Vector2d q = a + (b - a) * (double(j) / n);
        Eigen::Vector2d px;
        if (PrintSeenAt(gt, depth, camera, q, &px))
          piece.points.push_back(px);
        else
          flush();
      }
    }
    flush();
  }
  return out;
}

std::vector<std::vector<Eigen::Vector2d>> TrueOutlineInView(const GroundTruth& gt,
                                                            const PinholeCamera& camera,
                                                            double step_px) {
  const RasterResult& depth = gt.ViewRaster(camera);
  const double w = gt.flat_width - 1.0, h = gt.flat_height - 1.0;
  // Slightly inside the page so that every sample finds a surface point.
  const double e = 0.5;
  const Eigen::Vector2d corners[4] = {{e, e}, {w - e, e}, {w - e, h - e}, {e, h - e}};
  std::vector<std::vector<Eigen::Vector2d>> out;
  std::vector<Eigen::Vector2d> piece;
  auto flush = [&] {
    if (piece.size() >= 2) out.push_back(piece);
    piece.clear();
  };
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d a = corners[k], b = corners[(k + 1) % 4];
    const int n = std::max(1, int(std::ceil((b - a).norm() / step_px)));
    for (int j = 0; j <= n; ++j) {
      Eigen::Vector2d px;
      if (SeenAt(depth, camera, gt.SurfacePoint(a + (b - a) * (double(j) / n)), &px))
        piece.push_back(px);
      else
        flush();
    }
    flush();  // sides are kept apart
  }
  return out;
}

std::array<CornerView, 4> TrueCornersInView(const GroundTruth& gt, const PinholeCamera& camera,
                                            double margin_px) {
  const RasterResult& depth = gt.ViewRaster(camera);
  const double w = gt.flat_width - 1.0, h = gt.flat_height - 1.0, e = 0.5;
  const Eigen::Vector2d corners[4] = {{e, e}, {w - e, e}, {w - e, h - e}, {e, h - e}};
  std::array<CornerView, 4> out;
  out.fill(CornerView::kOutside);
  for (int i = 0; i < 4; ++i) {
    auto p3 = gt.SurfacePoint(corners[i]);
    if (!p3) continue;
    const Eigen::Vector3d xc = camera.CamFromWorld(*p3);
    const Eigen::Vector2d px = camera.ProjectCam(xc);
    if (xc.z() <= 0 || px.x() < margin_px || px.y() < margin_px ||
        px.x() > camera.width - 1 - margin_px || px.y() > camera.height - 1 - margin_px)
      continue;
    // Hidden when the surface in front of it is clearly nearer (a few pixels
    // around, since the corner sits on the silhouette).
    bool hidden = false;
    const int x = int(std::lround(px.x())), y = int(std::lround(px.y()));
    int covered = 0, nearer = 0;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        const float d = depth.depth(y + dy, x + dx);
        if (!std::isfinite(d)) continue;
        ++covered;
        nearer += d < xc.z() * (1 - 5e-3);
      }
    hidden = covered > 0 && nearer > covered / 2;
    out[i] = hidden ? CornerView::kHidden : CornerView::kVisible;
  }
  return out;
}

double ProjectedDiagonal(const GroundTruth& gt, const PinholeCamera& camera) {
  const auto c = TrueCorners(gt, camera);
  return 0.5 * ((c[2] - c[0]).norm() + (c[3] - c[1]).norm());
}

std::vector<TrueLine> TruthLines(const GroundTruth& gt) {
  return gt.lines.empty() ? LinesFromFlatScan(gt) : gt.lines;
}

bool LineRecallRequired(const GroundTruth& gt) {
  const fs::path synth = gt.root / "ground_truth" / "synth.json";
  if (fs::exists(synth)) {
    const Json doc = ReadJsonFile(synth);
    const std::string kind =
        doc.value("producer", Json::object()).value("options", Json::object()).value("kind", "");
    return kind == "text" || kind == "table";
  }
  int text = 0, rules = 0;
  double long_text = 0;
  for (const TrueLine& l : TruthLines(gt)) {
    if (l.kind == "rule") ++rules;
    if (l.kind != "text") continue;
    ++text;
    if ((l.points.back() - l.points.front()).norm() > 0.4 * gt.flat_width) ++long_text;
  }
  return rules >= 10 || (text >= 20 && long_text >= 0.5 * text);
}

}  // namespace docunfold::evaluate
