// The texture mapping proper: M projected into the reference view, the output
// size, every output pixel sampled from the reference image, the fill colour
// and the grid overlay.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "common/errors.h"
#include "common/statistics.h"
#include "common/texture_sampler.h"
#include "stages/render/render_internal.h"

namespace docunfold::render {
namespace {

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

}  // namespace

// The page region of the reference image: the boundary's outline filled.
cv::Mat1b OutlineMask(const Boundary& boundary, int width, int height) {
  cv::Mat1b mask(height, width, uchar(0));
  std::vector<cv::Point> polygon;
  for (const auto& p : boundary.contour)
    polygon.emplace_back(int(std::lround(p.x())), int(std::lround(p.y())));
  if (polygon.size() >= 3) cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{polygon}, 255);
  return mask;
}

// Projection of M into the reference view; which triangles face the camera
// (paper is seen from its printed side: the orientation of the majority of
// the projected area) and the reference image's pixel density on M': the
// median over faces inside the image of sqrt(image area / M' area).
ProjectedMesh ProjectMesh(const RenderInputs& in) {
  const MeshPair& m = in.meshes;
  const PinholeCamera& cam = in.camera;
  ProjectedMesh p;
  p.triangles = m.grid.Triangles();
  for (const auto& v : m.mesh3d) {
    p.cam.push_back(cam.CamFromWorld(v));
    p.pixel.push_back(cam.ProjectCam(p.cam.back()));
  }
  std::vector<double> signed_area(p.triangles.size());
  double positive = 0, negative = 0;
  for (size_t f = 0; f < p.triangles.size(); ++f) {
    const Triangle& t = p.triangles[f];
    const double a = 0.5 * Cross(p.pixel[t[1]] - p.pixel[t[0]], p.pixel[t[2]] - p.pixel[t[0]]);
    const double a2 = 0.5 * Cross(m.mesh2d[t[1]] - m.mesh2d[t[0]], m.mesh2d[t[2]] - m.mesh2d[t[0]]);
    // Orientation relative to M' (whose winding may be either way round).
    signed_area[f] = a2 >= 0 ? a : -a;
    (signed_area[f] > 0 ? positive : negative) += std::abs(a);
  }
  const double sign = positive >= negative ? 1 : -1;
  std::vector<double> ratios;
  p.front.resize(p.triangles.size());
  auto inside = [&](const Eigen::Vector2d& x) {
    return x.x() >= -0.5 && x.y() >= -0.5 && x.x() <= cam.width - 0.5 && x.y() <= cam.height - 0.5;
  };
  for (size_t f = 0; f < p.triangles.size(); ++f) {
    const Triangle& t = p.triangles[f];
    p.front[f] = signed_area[f] * sign > 0;
    if (!inside(p.pixel[t[0]]) || !inside(p.pixel[t[1]]) || !inside(p.pixel[t[2]])) continue;
    const double a2 =
        std::abs(0.5 * Cross(m.mesh2d[t[1]] - m.mesh2d[t[0]], m.mesh2d[t[2]] - m.mesh2d[t[0]]));
    if (!(a2 > 0) || !p.front[f]) continue;
    ratios.push_back(std::sqrt(std::abs(signed_area[f]) / a2));
  }
  p.faces_in_view = int(ratios.size());
  p.density = Median(ratios);
  p.raster = RasterizeMesh(cam, m.mesh3d, p.triangles);
  return p;
}

// Box of the part of M' the reference view sees (M's raster mapped to M').
Eigen::Vector4d VisibleBox(const RasterResult& raster, const std::vector<Triangle>& tris,
                           const std::vector<Eigen::Vector2d>& flat) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (int y = 0; y < raster.face.rows; ++y) {
    const int* face = raster.face.ptr<int>(y);
    const cv::Vec2f* bary = raster.bary.ptr<cv::Vec2f>(y);
    for (int x = 0; x < raster.face.cols; ++x) {
      if (face[x] < 0) continue;
      const Triangle& t = tris[face[x]];
      const double b1 = bary[x][0], b2 = bary[x][1];
      const Eigen::Vector2d q = (1 - b1 - b2) * flat[t[0]] + b1 * flat[t[1]] + b2 * flat[t[2]];
      x0 = std::min(x0, q.x());
      y0 = std::min(y0, q.y());
      x1 = std::max(x1, q.x());
      y1 = std::max(y1, q.y());
    }
  }
  return {x0, y0, x1, y1};
}

SizeChoice ChooseSize(const RenderOptions& o, double crop_w, double crop_h, double density) {
  SizeChoice s;
  if (o.width > 0) {
    s.rule = "width";
    s.scale = o.width / crop_w;
  } else if (o.height > 0) {
    s.rule = "height";
    s.scale = o.height / crop_h;
  } else if (o.dpi > 0) {
    s.rule = "dpi";
    s.scale = o.page_width_mm > 0 ? o.dpi * o.page_width_mm / 25.4 / crop_w
                                  : o.dpi * o.page_height_mm / 25.4 / crop_h;
  } else if (o.scale > 0) {
    s.rule = "scale";
    s.scale = o.scale * density;
  } else {
    s.rule = "reference-density";
    s.scale = density;
  }
  auto dims = [&] {
    s.width = o.width > 0 ? o.width : std::max(1, int(std::lround(crop_w * s.scale)));
    s.height = o.height > 0 ? o.height : std::max(1, int(std::lround(crop_h * s.scale)));
  };
  dims();
  const double pixels = double(s.width) * s.height;
  if (pixels > o.max_pixels) {
    if (s.rule != "reference-density")
      throw UsageError("the requested size " + std::to_string(s.width) + "x" +
                       std::to_string(s.height) + " exceeds --max-pixels " +
                       std::to_string(int64_t(o.max_pixels)));
    s.scale *= std::sqrt(o.max_pixels / pixels) * 0.999;
    s.capped = true;
    dims();
  }
  return s;
}

SampleStats SamplePixels(const RenderOptions& options, const RenderInputs& in,
                         const cv::Mat& reference, const ProjectedMesh& pm,
                         const std::vector<Eigen::Vector2d>& flat, const RasterResult& out_raster,
                         const RasterResult& ref_raster, double scale, cv::Mat3b* image,
                         cv::Mat1b* state) {
  const PinholeCamera& cam = in.camera;
  const int W = out_raster.face.cols, H = out_raster.face.rows;
  *image = cv::Mat3b(H, W, cv::Vec3b(0, 0, 0));
  *state = cv::Mat1b(H, W, kOutside);
  // Per triangle: d(camera point)/d(output pixel).
  const std::vector<Eigen::Matrix<double, 3, 2>> dx_dpix =
      SurfacePerOutputPixel(pm.cam, flat, pm.triangles, scale);
  double diag = 0;
  {
    Eigen::Vector3d lo = pm.cam[0], hi = lo;
    for (const auto& v : pm.cam) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    diag = (hi - lo).norm();
  }
  // A sample is hidden when the reference view's nearest surface around its
  // pixel is in front of it by more than this (relative to the page's size,
  // as every tolerance on the surface).
  const double depth_tolerance = 0.005 * diag;
  const TextureSampler sampler(reference);
  const Eigen::Matrix3d& K = cam.K;
  std::vector<SampleStats> rows(H);
  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      const int* face = out_raster.face.ptr<int>(y);
      const cv::Vec2f* bary = out_raster.bary.ptr<cv::Vec2f>(y);
      cv::Vec3b* out = image->ptr<cv::Vec3b>(y);
      uchar* st = state->ptr<uchar>(y);
      SampleStats& stats = rows[y];
      for (int x = 0; x < W; ++x) {
        const int f = face[x];
        if (f < 0) continue;
        const Triangle& t = pm.triangles[f];
        const double b1 = bary[x][0], b2 = bary[x][1];
        const Eigen::Vector3d X =
            (1 - b1 - b2) * pm.cam[t[0]] + b1 * pm.cam[t[1]] + b2 * pm.cam[t[2]];
        const Eigen::Vector3d h = K * X;
        const double u = h.x() / h.z(), v = h.y() / h.z();
        const bool in_image =
            h.z() > 0 && u >= -0.5 && v >= -0.5 && u <= cam.width - 0.5 && v <= cam.height - 0.5;
        bool seen = in_image && pm.front[f];
        if (seen) {
          // Depth test against the nearest surface at the 2x2 pixels around.
          const int u0 = int(std::floor(u)), v0 = int(std::floor(v));
          double nearest = -1;
          for (int dv = 0; dv <= 1; ++dv)
            for (int du = 0; du <= 1; ++du) {
              const int uu = std::clamp(u0 + du, 0, cam.width - 1);
              const int vv = std::clamp(v0 + dv, 0, cam.height - 1);
              const float d = ref_raster.depth(vv, uu);
              if (std::isfinite(d)) nearest = std::max(nearest, double(d));
            }
          if (nearest > 0 && X.z() > nearest + depth_tolerance) seen = false;
        }
        if (!seen) {
          ++stats.hidden;
          // Outside the image there is nothing to sample, even on request.
          if (!options.sample_hidden || !in_image) {
            st[x] = kHidden;
            continue;
          }
          st[x] = kHiddenSampled;
        } else {
          st[x] = kPage;
          ++stats.page;
        }
        // Footprint: d(u,v)/d(X) of the projection times d(X)/d(pixel).
        const Eigen::Matrix2d J = cam.ProjectCamJacobian(X) * dx_dpix[f];
        const float Jf[4] = {float(J(0, 0)), float(J(0, 1)), float(J(1, 0)), float(J(1, 1))};
        float c[3];
        if (sampler.Sample(float(u), float(v), Jf, options.antialias, c)) ++stats.minified;
        out[x] = cv::Vec3b(cv::saturate_cast<uchar>(c[0]), cv::saturate_cast<uchar>(c[1]),
                           cv::saturate_cast<uchar>(c[2]));
      }
    }
  });
  SampleStats total;
  for (const auto& r : rows) {
    total.page += r.page;
    total.hidden += r.hidden;
    total.minified += r.minified;
  }
  return total;
}

// Per-channel median colour of the page pixels (the paper, on a document).
cv::Vec3b MedianColour(const cv::Mat3b& image, const cv::Mat1b& state) {
  std::array<std::array<long, 256>, 3> hist{};
  long n = 0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      if (state(y, x) != kPage) continue;
      const cv::Vec3b& p = image(y, x);
      for (int c = 0; c < 3; ++c) ++hist[c][p[c]];
      ++n;
    }
  if (n == 0) return {255, 255, 255};
  cv::Vec3b out;
  for (int c = 0; c < 3; ++c) {
    long seen = 0;
    int v = 0;
    while (v < 255 && (seen += hist[c][v]) * 2 < n) ++v;
    out[c] = uchar(v);
  }
  return out;
}

// The edges of M' over the image: every k-th grid line (k keeps drawn lines
// at least `min_spacing` pixels apart) and always the border rows/columns;
// points of M' that the reference view does not see are tinted.
cv::Mat3b DrawGrid(const cv::Mat3b& image, const cv::Mat1b& state, const MeshPair& m,
                   const std::vector<Eigen::Vector2d>& flat, const PixelFrame& frame,
                   const cv::Scalar& colour, double min_spacing, int* step) {
  cv::Mat3b out = image.clone();
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x)
      if (state(y, x) == kHidden || state(y, x) == kHiddenSampled) {
        cv::Vec3b& p = out(y, x);
        p = cv::Vec3b(uchar(0.6 * p[0] + 0.4 * 200), uchar(0.6 * p[1] + 0.4 * 80),
                      uchar(0.6 * p[2] + 0.4 * 200));
      }
  const QuadGrid& g = m.grid;
  std::vector<double> lengths;
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c + 1 < g.nx; ++c)
      lengths.push_back(
          (frame.ToPixel(flat[g.Index(r, c + 1)]) - frame.ToPixel(flat[g.Index(r, c)])).norm());
  for (int r = 0; r + 1 < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c)
      lengths.push_back(
          (frame.ToPixel(flat[g.Index(r + 1, c)]) - frame.ToPixel(flat[g.Index(r, c)])).norm());
  const double spacing = Median(lengths);
  *step = spacing > 0 ? std::max(1, int(std::ceil(min_spacing / spacing))) : 1;
  constexpr int kShift = 4;  // sub-pixel vertex positions
  auto to_px = [&](int i) {
    const Eigen::Vector2d p = frame.ToPixel(flat[i]);
    return cv::Point(int(std::lround(p.x() * (1 << kShift))),
                     int(std::lround(p.y() * (1 << kShift))));
  };
  std::vector<std::vector<cv::Point>> lines;
  for (int r = 0; r < g.ny; ++r) {
    if (r % *step != 0 && r != g.ny - 1) continue;
    std::vector<cv::Point> line;
    for (int c = 0; c < g.nx; ++c) line.push_back(to_px(g.Index(r, c)));
    lines.push_back(std::move(line));
  }
  for (int c = 0; c < g.nx; ++c) {
    if (c % *step != 0 && c != g.nx - 1) continue;
    std::vector<cv::Point> line;
    for (int r = 0; r < g.ny; ++r) line.push_back(to_px(g.Index(r, c)));
    lines.push_back(std::move(line));
  }
  cv::polylines(out, lines, false, colour, 1, cv::LINE_AA, kShift);
  return out;
}

}  // namespace docunfold::render
