#include "stages/init-mesh/end_fold.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
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
    f.rays.push_back(
        (reference.R.transpose() * reference.CamRay(reference.Project(end))).normalized());
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

// The mismatch of all of M's silhouettes against the masks (fraction of the
// masks' total area).
double SilhouetteMismatch(const MeshPair& m, const std::vector<Silhouette>& views,
                          double total_area) {
  const EndLines rows{&m.grid, 0};
  double mismatch = 0;
  for (const Silhouette& view : views) {
    std::vector<std::optional<cv::Point2f>> px;
    px.reserve(m.mesh3d.size());
    for (const Eigen::Vector3d& x : m.mesh3d) px.push_back(view.Pixel(x));
    cv::Mat1b image = cv::Mat1b::zeros(view.mask.size());
    FillLines(rows, 0, rows.Lines() - 1, px, &image);
    mismatch += Mismatch(image, view.mask);
  }
  return mismatch / total_area;
}

// A flap beyond a hinge anywhere across an end, not only on a grid line: in
// M' the hinge is the line n·p' = offset + slope·(u·p' − u_mid), n the end's
// outward direction (along the page's sides) and u across it. The page beyond
// the hinge is turned about the hinge's image on M (a straight line fitted to
// it); its columns run on along n and it ends square to them, at the end
// offset the reference rays through M's end give (their median), or a given
// one.
class FreeFlap {
 public:
  FreeFlap(const MeshPair& m, const EndLines& lines, const PinholeCamera& reference)
      : m_(m), lines_(lines), locator_(m), centre_(reference.Center()) {
    const int w = lines.Width(), mid = std::max(1, (lines.Lines() - 1) / 2);
    Eigen::Vector2d n = Eigen::Vector2d::Zero();
    for (int j = 0; j < w; ++j)
      n += (m.mesh2d[size_t(lines.Vertex(0, j))] - m.mesh2d[size_t(lines.Vertex(mid, j))])
               .normalized();
    n_ = n.normalized();
    u_ = Eigen::Vector2d(-n_.y(), n_.x());
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Eigen::Vector2d& p : m.mesh2d) {
      lo = std::min(lo, n_.dot(p));
      hi = std::max(hi, n_.dot(p));
    }
    end_offset_ = hi;
    extent_ = hi - lo;
    for (int j = 0; j < w; ++j) {
      const Eigen::Vector3d end = m.mesh3d[size_t(lines.Vertex(0, j))];
      rays_.push_back(
          (reference.R.transpose() * reference.CamRay(reference.Project(end))).normalized());
      u_mid_ += u_.dot(m.mesh2d[size_t(lines.Vertex(0, j))]) / w;
    }
  }
  double end_offset() const { return end_offset_; }
  double extent() const { return extent_; }
  // The offset and slope of grid line `h` (a least-squares line through it).
  void GridLine(int h, double* offset, double* slope) const {
    Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
    Eigen::Vector2d b = Eigen::Vector2d::Zero();
    for (int j = 0; j < lines_.Width(); ++j) {
      const Eigen::Vector2d& p = m_.mesh2d[size_t(lines_.Vertex(h, j))];
      const Eigen::Vector2d row(1, u_.dot(p) - u_mid_);
      a += row * row.transpose();
      b += row * n_.dot(p);
    }
    const Eigen::Vector2d x = a.ldlt().solve(b);
    *offset = x[0];
    *slope = x[1];
  }
  // M with the flap turned through `angle` (radians) into `out`; the
  // stretch; 0 when the hinge does not cross M or no stretch fits the rays.
  double Place(double offset, double slope, double angle, double max_stretch, MeshPair* out,
               std::optional<double> fixed_end = std::nullopt, double* end_used = nullptr) const {
    const double norm = std::sqrt(1 + slope * slope);
    const Eigen::Vector2d out2 = (n_ - slope * u_) / norm, e = (u_ + slope * n_) / norm;
    const Eigen::Vector2d q0 = u_mid_ * u_ + offset * n_;
    // The hinge on M: a line fitted to its image, parametrised by M' length.
    double tau_lo = std::numeric_limits<double>::infinity(), tau_hi = -tau_lo;
    for (const Eigen::Vector2d& p : m_.mesh2d) {
      tau_lo = std::min(tau_lo, e.dot(p - q0));
      tau_hi = std::max(tau_hi, e.dot(p - q0));
    }
    constexpr int kSamples = 25;
    Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
    Eigen::Matrix<double, 2, 3> b = Eigen::Matrix<double, 2, 3>::Zero();
    Eigen::Vector3d before = Eigen::Vector3d::Zero();
    int found = 0, found_before = 0;
    double tau_found_lo = tau_hi, tau_found_hi = tau_lo;
    const double step_back = 0.05 * extent_;
    for (int k = 0; k < kSamples; ++k) {
      const double tau = tau_lo + (tau_hi - tau_lo) * (k + 0.5) / kSamples;
      const auto at = locator_.Locate(q0 + tau * e);
      if (!at) continue;
      const Eigen::Vector3d x = PointOnMesh3d(m_, *at);
      const Eigen::Vector2d row(1, tau);
      a += row * row.transpose();
      b += row * x.transpose();
      ++found;
      tau_found_lo = std::min(tau_found_lo, tau);
      tau_found_hi = std::max(tau_found_hi, tau);
      if (const auto back = locator_.Locate(q0 + tau * e - step_back * out2)) {
        before += x - PointOnMesh3d(m_, *back);
        ++found_before;
      }
    }
    if (found < 3 || found_before < 2 || tau_found_hi - tau_found_lo < 0.3 * (tau_hi - tau_lo))
      return 0;
    const Eigen::Matrix<double, 2, 3> line = a.ldlt().solve(b);
    const Eigen::Vector3d origin = line.row(0).transpose();
    const Eigen::Vector3d axis = line.row(1).transpose().normalized();
    const Eigen::Vector3d along = (before - before.dot(axis) * axis).normalized();
    const Eigen::Vector3d normal = axis.cross(along);
    const Eigen::Vector3d d = std::cos(angle) * along + std::sin(angle) * normal;
    // The flap is the page beyond the hinge: its columns run on along the
    // page's sides (n in M'), and it ends square to them, where the
    // reference rays through M's end put it (the median over the columns).
    const double cos_phi = n_.dot(out2), sin_phi = n_.dot(e);
    const Eigen::Vector3d along_flap = cos_phi * d + sin_phi * axis;
    const int w = lines_.Width();
    std::vector<Eigen::Vector2d> crossing(static_cast<size_t>(w), Eigen::Vector2d::Zero());
    std::vector<int> beyond(size_t(w), 0);  // vertices of the column past the hinge
    std::vector<double> ends;
    for (int j = 0; j < w; ++j) {
      int i = 0;
      while (i < lines_.Lines() && out2.dot(m_.mesh2d[size_t(lines_.Vertex(i, j))] - q0) > 0) ++i;
      if (i == 0 || i == lines_.Lines()) continue;
      const Eigen::Vector2d& a = m_.mesh2d[size_t(lines_.Vertex(i - 1, j))];
      const Eigen::Vector2d& b = m_.mesh2d[size_t(lines_.Vertex(i, j))];
      const double sa = out2.dot(a - q0), sb = out2.dot(b - q0);
      crossing[size_t(j)] = a + (b - a) * (sa / (sa - sb));
      beyond[size_t(j)] = i;
      const Eigen::Vector3d w0 = origin + e.dot(crossing[size_t(j)] - q0) * axis - centre_;
      const Eigen::Vector3d& r = rays_[size_t(j)];
      const double k = along_flap.dot(r);
      if (1 - k * k < 1e-3) continue;
      const double l = (k * r.dot(w0) - along_flap.dot(w0)) / (1 - k * k);
      if (l > 0 && r.dot(w0) + l * k > 0) ends.push_back(n_.dot(crossing[size_t(j)]) + l);
    }
    if (!fixed_end && ends.size() * 2 < size_t(w)) return 0;
    const double end = fixed_end ? *fixed_end : Median(ends);
    if (end_used) *end_used = end;
    *out = m_;
    double stretch = 0;
    for (int j = 0; j < w; ++j) {
      if (beyond[size_t(j)] == 0) continue;
      const Eigen::Vector2d& c = crossing[size_t(j)];
      const double before = n_.dot(m_.mesh2d[size_t(lines_.Vertex(0, j))] - c);
      const double length = end - n_.dot(c);
      if (!(before > 0) || !(length > 0) || length > max_stretch * before) return 0;
      stretch = std::max(stretch, length / before);
      const Eigen::Vector3d hinge = origin + e.dot(c - q0) * axis;
      for (int i = 0; i < beyond[size_t(j)]; ++i) {
        const size_t v = size_t(lines_.Vertex(i, j));
        const double f = std::clamp(n_.dot(m_.mesh2d[v] - c) / before, 0.0, 1.0);
        out->mesh3d[v] = hinge + f * length * along_flap;
        out->mesh2d[v] = c + f * length * n_;
      }
    }
    return stretch;
  }

 private:
  const MeshPair& m_;
  EndLines lines_;
  isometry::FlatMeshLocator locator_;
  Eigen::Vector3d centre_;
  Eigen::Vector2d n_, u_;
  double u_mid_ = 0, end_offset_ = 0, extent_ = 0;
  std::vector<Eigen::Vector3d> rays_;
};

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
  for (int h = 1; h <= max_hinge; ++h) {
    const Flap flap = MakeFlap(m, lines, h, reference);
    std::vector<cv::Mat1b> base(views.size());
    for (size_t v = 0; v < views.size(); ++v) {
      base[v] = cv::Mat1b::zeros(views[v].mask.size());
      FillLines(lines, h, lines.Lines() - 1, pixels[v], &base[v]);
    }
    MeshPair trial = m;
    auto score = [&](double angle_deg, double* length) {
      const double angle = angle_deg * kPi / 180;
      *length = FlapLength(flap, angle);
      if (!(*length > 0) || *length > o.max_length_ratio * flap.current_length) return -1.0;
      PlaceFlap(flap, lines, h, angle, *length, &trial);
      double mismatch = 0;
      for (size_t v = 0; v < views.size(); ++v) {
        std::vector<std::optional<cv::Point2f>> px = pixels[v];
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

// A grid line's fold refined into a free hinge (FreeFlap): coordinate descent
// over the angle, the hinge's offset and its slope, from the grid line's own.
struct FreeFold {
  double offset = 0, slope = 0, angle_deg = 0, mismatch = 0, length = 0;
  MeshPair meshes;
  std::optional<double> end;
};
std::optional<FreeFold> RefineFreeHinge(const MeshPair& m, const EndLines& lines,
                                        const PinholeCamera& reference,
                                        const std::vector<Silhouette>& views, double total_area,
                                        const EndFold& grid_fold, const EndFoldOptions& o) {
  const FreeFlap flap(m, lines, reference);
  FreeFold best;
  flap.GridLine(grid_fold.hinge_line, &best.offset, &best.slope);
  best.angle_deg = grid_fold.angle_deg;
  best.mismatch = std::numeric_limits<double>::infinity();
  MeshPair trial;
  const double min_offset = flap.end_offset() - o.max_flap_fraction * flap.extent();
  auto consider = [&](double offset, double slope, double angle_deg,
                      std::optional<double> end = std::nullopt) {
    if (offset < min_offset || offset >= flap.end_offset()) return;
    double end_used = 0;
    const double stretch = flap.Place(offset, slope, angle_deg * kPi / 180, o.max_length_ratio,
                                      &trial, end, &end_used);
    if (!(stretch > 0)) return;
    const double mismatch = SilhouetteMismatch(trial, views, total_area);
    if (mismatch < best.mismatch) {
      best = {offset, slope, angle_deg, mismatch, end_used - offset, trial, end_used};
    }
  };
  consider(best.offset, best.slope, best.angle_deg);
  consider(best.offset, 0, best.angle_deg);
  // The flap's frame may turn the other way round from the grid line's.
  const double grid_offset = best.offset, grid_slope = best.slope, grid_angle = best.angle_deg;
  consider(grid_offset, grid_slope, -grid_angle);
  consider(grid_offset, 0, -grid_angle);
  if (!std::isfinite(best.mismatch)) return std::nullopt;
  const double offset_step = 0.004 * flap.extent();
  for (int round = 0; round < 4; ++round) {
    const FreeFold start = best;
    const double end = *best.end;
    for (int k = -6; k <= 6; ++k) consider(best.offset, best.slope, start.angle_deg + k, end);
    const double angle = best.angle_deg, slope = best.slope, offset = best.offset;
    for (int k = -10; k <= 10; ++k) consider(offset + k * offset_step, slope, angle, end);
    const double at = best.offset;
    for (int k = -15; k <= 15; ++k) consider(at, slope + 0.01 * k, angle, end);
    const double slope_now = best.slope;
    for (int k = -15; k <= 15; ++k) consider(at, slope_now, angle, end + k * offset_step);
    if (best.mismatch >= start.mismatch) break;
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
      if (o.free_hinge) {
        auto free = RefineFreeHinge(*m, lines, reference, views, total_area, best, o);
        if (free && free->mismatch < best.mismatch_after) {
          folded = std::move(free->meshes);
          best.mismatch_after = free->mismatch;
          best.angle_deg = free->angle_deg;
          best.length = free->length;
          best.hinge_slope = free->slope;
          best.free_hinge = true;
        }
        const double free_gain = best.mismatch_before - best.mismatch_after;
        best.kept = free_gain >= o.min_gain * best.mismatch_before && free_gain >= o.min_gain_area;
      }
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
