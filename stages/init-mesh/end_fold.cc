#include "stages/init-mesh/end_fold.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "common/isometry/mesh_index.h"
#include "common/isometry/metrics.h"
#include "common/statistics.h"

namespace docunfold::init_mesh {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Grid lines counted from one end: line 0 is the end itself.
struct EndLines {
  const QuadGrid* grid;
  int end;
  int Lines() const { return end < 2 ? grid->ny : grid->nx; }
  int Width() const { return end < 2 ? grid->nx : grid->ny; }
  int Vertex(int line, int j) const {
    switch (end) {
      case 0:
        return grid->Index(line, j);
      case 1:
        return grid->Index(grid->ny - 1 - line, j);
      case 2:
        return grid->Index(j, line);
      default:
        return grid->Index(j, grid->nx - 1 - line);
    }
  }
};

// A photo's page mask at the comparison's scale, and where M's vertices fall
// in it.
struct Silhouette {
  const ViewPage* photo;
  double scale;
  cv::Mat1b mask;  // 0 or 255
  double area;
  std::optional<cv::Point2f> Pixel(const Eigen::Vector3d& x) const {
    const auto px = ProjectDistorted(photo->camera, photo->distortion, x);
    if (!px || !px->allFinite()) return std::nullopt;
    return cv::Point2f(float(px->x() * scale), float(px->y() * scale));
  }
};

// Fills the quads between lines [first, last) of `lines` into `image`; a quad
// with a corner behind the camera is left out.
void FillLines(const EndLines& lines, int first, int last,
               const std::vector<std::optional<cv::Point2f>>& pixels, cv::Mat1b* image) {
  constexpr int kShift = 4;
  auto fixed = [](const cv::Point2f& p) {
    return cv::Point(int(std::lround(p.x * (1 << kShift))), int(std::lround(p.y * (1 << kShift))));
  };
  for (int i = first; i < last; ++i)
    for (int j = 0; j + 1 < lines.Width(); ++j) {
      const int c[4] = {lines.Vertex(i, j), lines.Vertex(i, j + 1), lines.Vertex(i + 1, j + 1),
                        lines.Vertex(i + 1, j)};
      cv::Point corners[4];
      bool ok = true;
      for (int k = 0; k < 4 && ok; ++k) {
        const auto& p = pixels[size_t(c[k])];
        ok = p.has_value();
        if (ok) corners[k] = fixed(*p);
      }
      if (!ok) continue;
      const cv::Point t1[3] = {corners[0], corners[1], corners[2]};
      const cv::Point t2[3] = {corners[0], corners[2], corners[3]};
      cv::fillConvexPoly(*image, t1, 3, cv::Scalar(255), cv::LINE_8, kShift);
      cv::fillConvexPoly(*image, t2, 3, cv::Scalar(255), cv::LINE_8, kShift);
    }
}

double Mismatch(const cv::Mat1b& silhouette, const cv::Mat1b& mask) {
  cv::Mat1b diff;
  cv::bitwise_xor(silhouette, mask, diff);
  return double(cv::countNonZero(diff));
}

// The flap beyond hinge line `h` of `lines`: the hinge, the frame a turn
// about it is measured in, and the reference photo's rays through M's end,
// on which the flap's far edge stays.
struct Flap {
  std::vector<Eigen::Vector3d> hinge3d;
  std::vector<Eigen::Vector2d> hinge2d;
  Eigen::Vector3d along, normal;  // the panel's outward direction and normal at the hinge
  Eigen::Vector2d along2d;
  std::vector<Eigen::Vector3d> ray_origin_offsets;  // hinge − camera centre
  std::vector<Eigen::Vector3d> rays;                // world directions through the end
  double current_length = 0;
};

Flap MakeFlap(const MeshPair& m, const EndLines& lines, int h, const PinholeCamera& reference) {
  Flap f;
  const int w = lines.Width();
  Eigen::Vector3d along = Eigen::Vector3d::Zero();
  Eigen::Vector2d along2d = Eigen::Vector2d::Zero();
  const Eigen::Vector3d centre = reference.Center();
  for (int j = 0; j < w; ++j) {
    const size_t hv = size_t(lines.Vertex(h, j)), before = size_t(lines.Vertex(h + 1, j));
    f.hinge3d.push_back(m.mesh3d[hv]);
    f.hinge2d.push_back(m.mesh2d[hv]);
    along += (m.mesh3d[hv] - m.mesh3d[before]).normalized();
    along2d += (m.mesh2d[hv] - m.mesh2d[before]).normalized();
    const Eigen::Vector3d end = m.mesh3d[size_t(lines.Vertex(0, j))];
    f.rays.push_back(reference.RayDirection(reference.Project(end)));
    f.ray_origin_offsets.push_back(m.mesh3d[hv] - centre);
    for (int i = 0; i < h; ++i)
      f.current_length +=
          (m.mesh3d[size_t(lines.Vertex(i, j))] - m.mesh3d[size_t(lines.Vertex(i + 1, j))]).norm() /
          w;
  }
  const Eigen::Vector3d axis = (f.hinge3d.back() - f.hinge3d.front()).normalized();
  f.along = (along - along.dot(axis) * axis).normalized();
  f.normal = axis.cross(f.along);
  const Eigen::Vector2d axis2d = (f.hinge2d.back() - f.hinge2d.front()).normalized();
  f.along2d = (along2d - along2d.dot(axis2d) * axis2d).normalized();
  return f;
}

// The flap's length at `angle`: the median over the end's vertices of where
// the flap's line meets (comes closest to) the reference ray; 0 when none.
double FlapLength(const Flap& f, double angle) {
  const Eigen::Vector3d d = std::cos(angle) * f.along + std::sin(angle) * f.normal;
  std::vector<double> lengths;
  for (size_t j = 0; j < f.rays.size(); ++j) {
    const Eigen::Vector3d& r = f.rays[j];
    const Eigen::Vector3d& w0 = f.ray_origin_offsets[j];
    const double k = d.dot(r);
    if (1 - k * k < 1e-3) continue;
    const double length = (k * r.dot(w0) - d.dot(w0)) / (1 - k * k);
    const double s = r.dot(w0) + length * k;
    if (length > 0 && s > 0) lengths.push_back(length);
  }
  if (lengths.size() * 2 < f.rays.size()) return 0;
  return Median(lengths);
}

void PlaceFlap(const Flap& f, const EndLines& lines, int h, double angle, double length,
               MeshPair* m) {
  const Eigen::Vector3d d = std::cos(angle) * f.along + std::sin(angle) * f.normal;
  for (int i = 0; i < h; ++i) {
    const double t = double(h - i) / double(h);
    for (int j = 0; j < lines.Width(); ++j) {
      const size_t v = size_t(lines.Vertex(i, j));
      m->mesh3d[v] = f.hinge3d[size_t(j)] + t * length * d;
      m->mesh2d[v] = f.hinge2d[size_t(j)] + t * length * f.along2d;
    }
  }
}

// Whether the reference photo cuts M's end off: an end vertex within
// `margin` pixels of the image border (the end is then not the page's side,
// and the rays through it do not bound a flap).
bool EndAtImageBorder(const MeshPair& m, const EndLines& lines, const PinholeCamera& reference,
                      double margin) {
  for (int j = 0; j < lines.Width(); ++j) {
    const Eigen::Vector2d px = reference.Project(m.mesh3d[size_t(lines.Vertex(0, j))]);
    if (!(px.x() > margin && px.y() > margin && px.x() < reference.width - 1 - margin &&
          px.y() < reference.height - 1 - margin))
      return true;
  }
  return false;
}

// The fraction of `points` within `distance` of `before` and not of `after`,
// less the fraction the other way.
double PointsLost(const MeshPair& before, const MeshPair& after,
                  const std::vector<Eigen::Vector3d>& points, double distance) {
  if (points.empty()) return 0;
  const auto triangles = before.grid.Triangles();
  const isometry::TriangleMeshIndex old_index(before.mesh3d, triangles);
  const isometry::TriangleMeshIndex new_index(after.mesh3d, triangles);
  int lost = 0;
  for (const Eigen::Vector3d& p : points) {
    const bool was = old_index.Closest(p, distance).has_value();
    const bool is = new_index.Closest(p, distance).has_value();
    lost += int(was) - int(is);
  }
  return double(lost) / double(points.size());
}

// The best hinge and angle of one end against the silhouettes (hinge_line 0:
// none found).
EndFold SearchEnd(const MeshPair& m, const EndLines& lines, const PinholeCamera& reference,
                  const std::vector<Silhouette>& views, double total_area,
                  const EndFoldOptions& o) {
  EndFold best;
  best.end = lines.end;
  const int max_hinge =
      std::min(lines.Lines() - 2, int(std::floor(o.max_flap_fraction * (lines.Lines() - 1))));
  if (max_hinge < 1 || EndAtImageBorder(m, lines, reference, o.border_margin_px)) return best;
  std::vector<std::vector<std::optional<cv::Point2f>>> pixels(views.size());
  double before = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    for (const Eigen::Vector3d& x : m.mesh3d) pixels[v].push_back(views[v].Pixel(x));
    cv::Mat1b all = cv::Mat1b::zeros(views[v].mask.size());
    FillLines(lines, 0, lines.Lines() - 1, pixels[v], &all);
    before += Mismatch(all, views[v].mask);
  }
  best.mismatch_before = best.mismatch_after = before / total_area;
  // A trial overwrites only the flap's lines [0, h) of these, and h grows:
  // one copy serves every hinge.
  MeshPair trial = m;
  std::vector<std::vector<std::optional<cv::Point2f>>> trial_pixels = pixels;
  for (int h = 1; h <= max_hinge; ++h) {
    const Flap flap = MakeFlap(m, lines, h, reference);
    std::vector<cv::Mat1b> base(views.size());
    for (size_t v = 0; v < views.size(); ++v) {
      base[v] = cv::Mat1b::zeros(views[v].mask.size());
      FillLines(lines, h, lines.Lines() - 1, pixels[v], &base[v]);
    }
    auto score = [&](double angle_deg, double* length) {
      const double angle = angle_deg * kPi / 180;
      *length = FlapLength(flap, angle);
      if (!(*length > 0) || *length > o.max_length_ratio * flap.current_length) return -1.0;
      PlaceFlap(flap, lines, h, angle, *length, &trial);
      double mismatch = 0;
      for (size_t v = 0; v < views.size(); ++v) {
        std::vector<std::optional<cv::Point2f>>& px = trial_pixels[v];
        for (int i = 0; i < h; ++i)
          for (int j = 0; j < lines.Width(); ++j) {
            const size_t idx = size_t(lines.Vertex(i, j));
            px[idx] = views[v].Pixel(trial.mesh3d[idx]);
          }
        cv::Mat1b image = base[v].clone();
        FillLines(lines, 0, h, px, &image);
        mismatch += Mismatch(image, views[v].mask);
      }
      return mismatch / total_area;
    };
    double coarse_best = -1, coarse_angle = 0, length = 0;
    for (double a = -o.max_angle_deg; a <= o.max_angle_deg + 1e-9; a += o.coarse_step_deg) {
      const double s = score(a, &length);
      if (s >= 0 && (coarse_best < 0 || s < coarse_best)) {
        coarse_best = s;
        coarse_angle = a;
      }
    }
    if (coarse_best < 0) continue;
    for (double a = coarse_angle - o.coarse_step_deg; a <= coarse_angle + o.coarse_step_deg;
         a += 1) {
      const double s = score(a, &length);
      if (s >= 0 && s < best.mismatch_after) {
        best.mismatch_after = s;
        best.hinge_line = h;
        best.angle_deg = a;
        best.length = length;
      }
    }
  }
  return best;
}

}  // namespace

std::vector<EndFold> FoldEnds(const std::vector<ViewPage>& photos, const PinholeCamera& reference,
                              const std::vector<Eigen::Vector3d>& points, const EndFoldOptions& o,
                              MeshPair* m) {
  std::vector<EndFold> folds;
  if (!o.enabled || photos.empty()) return folds;
  std::vector<Silhouette> views;
  double total_area = 0;
  for (const ViewPage& p : photos) {
    if (p.mask.empty()) continue;
    Silhouette s{&p, double(o.raster_width) / double(p.mask.cols), {}, 0};
    cv::Mat1b small;
    cv::resize(p.mask, small, cv::Size(o.raster_width, int(std::lround(p.mask.rows * s.scale))), 0,
               0, cv::INTER_AREA);
    s.mask = small > 127;
    s.area = double(cv::countNonZero(s.mask));
    total_area += s.area;
    views.push_back(std::move(s));
  }
  if (views.empty() || total_area <= 0) return folds;
  for (int end = 0; end < 4; ++end) {
    const EndLines lines{&m->grid, end};
    EndFold best = SearchEnd(*m, lines, reference, views, total_area, o);
    const double gain = best.mismatch_before - best.mismatch_after;
    best.kept =
        best.hinge_line > 0 && gain >= o.min_gain * best.mismatch_before && gain >= o.min_gain_area;
    MeshPair folded = *m;
    if (best.hinge_line > 0) {
      const Flap flap = MakeFlap(*m, lines, best.hinge_line, reference);
      PlaceFlap(flap, lines, best.hinge_line, best.angle_deg * kPi / 180, best.length, &folded);
      best.points_lost = PointsLost(*m, folded, points, o.point_distance * isometry::ModelSize(*m));
      best.kept = best.kept && best.points_lost <= o.max_points_lost;
    }
    if (best.kept) {
      m->mesh3d = folded.mesh3d;
      m->mesh2d = folded.mesh2d;
    }
    if (best.hinge_line > 0 || best.mismatch_before > 0) folds.push_back(best);
  }
  return folds;
}

}  // namespace docunfold::init_mesh
