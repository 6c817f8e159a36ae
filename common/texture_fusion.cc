#include "common/texture_fusion.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <opencv2/imgproc/detail/gcgraph.hpp>

#include "common/program.h"
#include "common/statistics.h"
#include "common/texture_fusion_internal.h"
#include "common/texture_sampler.h"

namespace docunfold {
namespace {

using fusion_internal::ViewRendering;

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Smaller singular value of a 2x2 matrix.
double MinSingularValue(const Eigen::Matrix2d& J) {
  const double a = J.squaredNorm(), d = std::abs(J.determinant());
  const double disc = std::sqrt(std::max(0.0, a * a - 4 * d * d));
  return std::sqrt(std::max(0.0, 0.5 * (a - disc)));
}

// Per triangle, the signed area of its image in `camera` (pinhole) relative
// to its area in the output: positive where the camera sees it the same way
// round as the output shows it.
std::vector<double> SignedAreas(const FusionSurface& s, const PinholeCamera& camera) {
  std::vector<double> out(s.triangles.size(), 0);
  std::vector<Eigen::Vector2d> px(s.world.size());
  std::vector<char> ahead(s.world.size());
  for (size_t i = 0; i < s.world.size(); ++i) {
    const Eigen::Vector3d c = camera.CamFromWorld(s.world[i]);
    ahead[i] = c.z() > 0;
    if (ahead[i]) px[i] = camera.ProjectCam(c);
  }
  for (size_t f = 0; f < s.triangles.size(); ++f) {
    const Triangle& t = s.triangles[f];
    if (!ahead[t[0]] || !ahead[t[1]] || !ahead[t[2]]) continue;
    const double a = Cross(px[t[1]] - px[t[0]], px[t[2]] - px[t[0]]);
    const double o = Cross(s.pixel[t[1]] - s.pixel[t[0]], s.pixel[t[2]] - s.pixel[t[0]]);
    out[f] = o >= 0 ? a : -a;
  }
  return out;
}

// Renders the surface from `view`: every output pixel on a triangle that the
// view sees from the printed side (`printed_sign`: the sign of SignedAreas
// the reference sees), in front of it, unhidden, inside the frame and mask.
ViewRendering RenderView(const FusionSurface& s, const RasterResult& out_raster,
                         const std::vector<Eigen::Matrix<double, 3, 2>>& dx_dpix,
                         const FusionView& view, double printed_sign, double depth_tolerance,
                         bool antialias) {
  const PinholeCamera& cam = view.camera;
  const int W = s.width, H = s.height;
  ViewRendering r{cv::Mat3b(H, W, cv::Vec3b(0, 0, 0)), cv::Mat1f(H, W, 0.0f),
                  cv::Mat1b(H, W, uchar(0))};
  const std::vector<double> areas = SignedAreas(s, cam);
  // The depth buffer at up to ~2 megapixels: it only has to say which
  // surface is nearest, not where exactly its edge runs.
  const double depth_scale =
      std::min(1.0, std::sqrt(2e6 / (double(cam.width) * double(cam.height))));
  const RasterResult depth = RasterizeMesh(cam, s.world, s.triangles, depth_scale);
  cv::Mat1b mask;
  if (!view.mask.empty()) {
    // Away from the mask's edge: a photo's pixels there mix in the table.
    const int r_px = std::max(2, int(std::lround(0.002 * std::hypot(cam.width, cam.height))));
    cv::erode(view.mask, mask,
              cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r_px + 1, 2 * r_px + 1)));
  }
  const bool distorted = view.distortion != std::array<double, 4>{};
  const TextureSampler sampler(view.photo);
  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      const int* face = out_raster.face.ptr<int>(y);
      const cv::Vec2f* bary = out_raster.bary.ptr<cv::Vec2f>(y);
      for (int x = 0; x < W; ++x) {
        const int f = face[x];
        if (f < 0 || !(areas[f] * printed_sign > 0)) continue;
        const Triangle& t = s.triangles[f];
        const double b1 = bary[x][0], b2 = bary[x][1];
        const Eigen::Vector3d X =
            (1 - b1 - b2) * s.world[t[0]] + b1 * s.world[t[1]] + b2 * s.world[t[2]];
        const Eigen::Vector3d xc = cam.CamFromWorld(X);
        if (!(xc.z() > 0)) continue;
        const Eigen::Vector2d p = cam.ProjectCam(xc);
        // Depth test against the nearest surface at the 2x2 buffer pixels around.
        const double du = p.x() * depth_scale, dv = p.y() * depth_scale;
        const int u0 = int(std::floor(du)), v0 = int(std::floor(dv));
        double nearest = -1;
        for (int j = 0; j <= 1; ++j)
          for (int i = 0; i <= 1; ++i) {
            const int uu = u0 + i, vv = v0 + j;
            if (uu < 0 || vv < 0 || uu >= depth.depth.cols || vv >= depth.depth.rows) continue;
            const float d = depth.depth(vv, uu);
            if (std::isfinite(d)) nearest = std::max(nearest, double(d));
          }
        if (nearest > 0 && xc.z() > nearest + depth_tolerance) continue;
        Eigen::Vector2d q = p;
        if (distorted) {
          const auto d = ProjectDistorted(cam, view.distortion, X);
          if (!d) continue;
          q = *d;
        }
        if (!(q.x() >= 0 && q.y() >= 0 && q.x() <= cam.width - 1 && q.y() <= cam.height - 1))
          continue;
        if (!mask.empty() && !mask(int(std::lround(q.y())), int(std::lround(q.x())))) continue;
        const Eigen::Matrix2d J = cam.ProjectCamJacobian(xc) * cam.R * dx_dpix[f];
        const float Jf[4] = {float(J(0, 0)), float(J(0, 1)), float(J(1, 0)), float(J(1, 1))};
        float c[3];
        if (sampler.Sample(float(q.x()), float(q.y()), Jf, antialias, c)) r.minified(y, x) = 255;
        r.colour(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(c[0]), cv::saturate_cast<uchar>(c[1]),
                                   cv::saturate_cast<uchar>(c[2]));
        r.resolution(y, x) = float(std::max(1e-6, MinSingularValue(J)));
      }
    }
  });
  return r;
}

// Alpha-expansion (Boykov, Veksler and Zabih 2001) over a grid of patches:
// data[p * n + l] the cost of label l at patch p, seam(p, q, a, b) the cost
// of neighbours p, q labelled a, b (a metric). Starts from `labels`.
template <typename Seam>
void AlphaExpansion(int gw, int gh, int n, const std::vector<double>& data, const Seam& seam,
                    std::vector<int>* labels) {
  const int P = gw * gh;
  std::vector<int>& f = *labels;
  auto energy = [&] {
    double e = 0;
    for (int p = 0; p < P; ++p) e += data[size_t(p) * n + f[p]];
    for (int y = 0; y < gh; ++y)
      for (int x = 0; x < gw; ++x) {
        const int p = y * gw + x;
        if (x + 1 < gw) e += seam(p, p + 1, f[p], f[p + 1]);
        if (y + 1 < gh) e += seam(p, p + gw, f[p], f[p + gw]);
      }
    return e;
  };
  double best = energy();
  for (int cycle = 0; cycle < 4; ++cycle) {
    bool improved = false;
    for (int alpha = 0; alpha < n; ++alpha) {
      cv::detail::GCGraph<double> graph(P, 4 * P);
      std::vector<double> source(P, 0), sink(P, 0);  // cost of alpha, cost of keeping
      for (int p = 0; p < P; ++p) {
        graph.addVtx();
        source[p] = data[size_t(p) * n + alpha];
        sink[p] = data[size_t(p) * n + f[p]];
      }
      auto pair = [&](int p, int q) {
        const double A = seam(p, q, f[p], f[q]), B = seam(p, q, f[p], alpha),
                     C = seam(p, q, alpha, f[q]);
        // E(xp, xq), 1 = alpha: A + (C - A) xp - C xq + (B + C - A)(1 - xp) xq.
        if (C > A)
          source[p] += C - A;
        else
          sink[p] += A - C;
        sink[q] += C;
        graph.addEdges(p, q, std::max(0.0, B + C - A), 0);
      };
      for (int y = 0; y < gh; ++y)
        for (int x = 0; x < gw; ++x) {
          const int p = y * gw + x;
          if (x + 1 < gw) pair(p, p + 1);
          if (y + 1 < gh) pair(p, p + gw);
        }
      for (int p = 0; p < P; ++p) {
        const double m = std::min(source[p], sink[p]);
        graph.addTermWeights(p, source[p] - m, sink[p] - m);
      }
      graph.maxFlow();
      std::vector<int> next = f;
      for (int p = 0; p < P; ++p)
        if (!graph.inSourceSegment(p)) next[p] = alpha;
      std::swap(f, next);
      const double e = energy();
      if (e < best - 1e-9) {
        best = e;
        improved = true;
      } else {
        std::swap(f, next);  // no better (or worse through a clamped term)
      }
    }
    if (!improved) break;
  }
}

// A view other than the reference that sees a point pays this where it
// should not colour it (the reference's border band), and a view pays it per
// pixel of a patch it does not see.
constexpr double kMissCost = 20;

// Per pixel and view: the data cost (resolution, the reference's
// preference, outliers, the reference's border band), +inf where the view
// does not see the point.
std::vector<cv::Mat1f> DataCosts(const FusionOptions& o, const std::vector<ViewRendering>& r,
                                 const std::vector<double>& sharpness,
                                 const cv::Mat1b& on_surface) {
  const int n = int(r.size()), W = on_surface.cols, H = on_surface.rows;
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<cv::Mat1f> brightness(n);
  for (int v = 0; v < n; ++v) {
    cv::Mat grey;
    cv::cvtColor(r[v].colour, grey, cv::COLOR_BGR2GRAY);
    grey.convertTo(brightness[v], CV_32F);
    // Blurred where it is seen only, so that the empty black does not bleed in.
    cv::Mat1f w, b;
    r[v].Valid().convertTo(w, CV_32F, 1 / 255.0);
    cv::GaussianBlur(brightness[v].mul(w), b, cv::Size(0, 0), 3);
    cv::GaussianBlur(w, w, cv::Size(0, 0), 3);
    brightness[v] = b / (w + 1e-6f);
  }
  const double log_cap = std::log(o.resolution_cap), log_pref = std::log(o.reference_preference);
  cv::Mat1f border_distance;
  {
    cv::Mat1b padded;
    cv::copyMakeBorder(on_surface, padded, 1, 1, 1, 1, cv::BORDER_CONSTANT, 0);
    cv::distanceTransform(padded, border_distance, cv::DIST_L2, 3);
    border_distance = border_distance(cv::Rect(1, 1, W, H)).clone();
  }
  const float band = float(o.reference_border * std::hypot(W, H));
  // Each other view's disagreement with the reference (0..1) where both see.
  std::vector<cv::Mat1f> disagreement(n);
  {
    auto grey = [&](int v) {
      cv::Mat g;
      cv::cvtColor(r[v].colour, g, cv::COLOR_BGR2GRAY);
      cv::Mat1f f;
      g.convertTo(f, CV_32F, 1 / 255.0);
      cv::GaussianBlur(f, f, cv::Size(0, 0), 2);
      return f;
    };
    const cv::Mat1f reference = grey(0);
    for (int v = 1; v < n; ++v) {
      cv::Mat1f d = cv::abs(grey(v) - reference);
      cv::blur(d, disagreement[v], cv::Size(11, 11));
    }
  }
  std::vector<cv::Mat1f> cost(n);
  for (int v = 0; v < n; ++v) cost[v] = cv::Mat1f(H, W, inf);
  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range& range) {
    std::vector<float> seen_brightness;
    for (int y = range.start; y < range.end; ++y)
      for (int x = 0; x < W; ++x) {
        seen_brightness.clear();
        for (int u = 0; u < n; ++u)
          if (r[u].resolution(y, x) > 0) seen_brightness.push_back(brightness[u](y, x));
        const int seen_by = int(seen_brightness.size());
        if (seen_by == 0) continue;
        std::sort(seen_brightness.begin(), seen_brightness.end());
        const float median = seen_brightness[seen_by / 2];
        const float darkest = seen_brightness[0];
        const bool reference_sees = r[0].resolution(y, x) > 0;
        const bool reference_border = reference_sees && border_distance(y, x) < band;
        for (int v = 0; v < n; ++v) {
          const float res = r[v].resolution(y, x);
          if (!(res > 0)) continue;
          double c = std::max(
              0.0, log_cap - std::log(std::min<double>(res, o.resolution_cap) * sharpness[v]));
          if (v == 0) c = std::max(0.0, c - log_pref);
          const float b = brightness[v](y, x);
          if (seen_by >= 3 && std::abs(b - median) > o.outlier_ratio * median + 4)
            c += o.outlier_cost;
          if (seen_by == 2 && b > darkest * (1 + o.glare_ratio) + 4) c += o.outlier_cost;
          if (v > 0 && reference_border) c += kMissCost;
          if (v > 0 && reference_sees && disagreement[v](y, x) > o.reference_disagreement)
            c += o.outlier_cost;
          cost[v](y, x) = float(c);
        }
      }
  });
  return cost;
}

// One view per texel patch (patch_px square; row-major, `*patches_across`
// a row) by alpha-expansion over the data costs summed per patch and seams
// that cost the views' colour difference on both sides.
std::vector<int> PatchLabels(const FusionOptions& o, const std::vector<ViewRendering>& r,
                             const std::vector<cv::Mat1f>& cost, int* patches_across) {
  const int n = int(r.size()), W = cost[0].cols, H = cost[0].rows;
  const int p = std::max(1, o.patch_px);
  const int gw = (W + p - 1) / p, gh = (H + p - 1) / p, P = gw * gh;
  *patches_across = gw;
  std::vector<double> data(size_t(P) * n, 0);
  // Mean colour difference (0..1) between every two views per patch, 1
  // where either misses part of it.
  std::vector<float> diff(size_t(P) * n * n, 0);
  for (int by = 0; by < gh; ++by)
    for (int bx = 0; bx < gw; ++bx) {
      const int q = by * gw + bx;
      int seen_px = 0;
      std::vector<int> missing(n, 0);
      std::vector<double> sum(size_t(n) * n, 0);
      for (int y = by * p; y < std::min(H, (by + 1) * p); ++y)
        for (int x = bx * p; x < std::min(W, (bx + 1) * p); ++x) {
          bool any = false;
          for (int v = 0; v < n; ++v) any |= std::isfinite(cost[v](y, x));
          if (!any) continue;
          ++seen_px;
          for (int v = 0; v < n; ++v) {
            const float c = cost[v](y, x);
            if (std::isfinite(c))
              data[size_t(q) * n + v] += c;
            else
              ++missing[v];
          }
          for (int a = 0; a < n; ++a)
            for (int b = a + 1; b < n; ++b) {
              const cv::Vec3b ca = r[a].colour(y, x), cb = r[b].colour(y, x);
              sum[size_t(a) * n + b] +=
                  (std::abs(ca[0] - cb[0]) + std::abs(ca[1] - cb[1]) + std::abs(ca[2] - cb[2])) /
                  (3 * 255.0);
            }
        }
      for (int v = 0; v < n; ++v) data[size_t(q) * n + v] += kMissCost * missing[v];
      for (int a = 0; a < n; ++a)
        for (int b = a + 1; b < n; ++b) {
          const float d = seen_px == 0                  ? 0.0f
                          : missing[a] + missing[b] > 0 ? 1.0f
                                                        : float(sum[size_t(a) * n + b] / seen_px);
          diff[(size_t(q) * n + a) * n + b] = diff[(size_t(q) * n + b) * n + a] = d;
        }
    }
  std::vector<int> labels(P, 0);
  for (int q = 0; q < P; ++q)
    for (int v = 1; v < n; ++v)
      if (data[size_t(q) * n + v] < data[size_t(q) * n + labels[q]]) labels[q] = v;
  // A seam costs the photos' difference on both sides of it along its
  // length, and a little even where they agree.
  const double seam_scale = o.seam_weight * p;
  auto seam = [&](int a_patch, int b_patch, int a, int b) -> double {
    if (a == b) return 0;
    const double d =
        diff[(size_t(a_patch) * n + a) * n + b] + diff[(size_t(b_patch) * n + a) * n + b];
    return seam_scale * (0.05 + 0.5 * d);
  };
  if (n > 1) AlphaExpansion(gw, gh, n, data, seam, &labels);
  return labels;
}

// Each pixel from its patch's view (or, where that view misses it, the
// cheapest that sees it), blended across seams: out->image, label, seen,
// minified.
void Blend(const FusionOptions& o, const std::vector<ViewRendering>& r,
           const std::vector<cv::Mat1f>& cost, const std::vector<int>& labels, int patches_across,
           const cv::Mat1b& on_surface, FusedTexture* out) {
  const int n = int(r.size()), W = on_surface.cols, H = on_surface.rows;
  const int p = std::max(1, o.patch_px);
  cv::Mat1b pixel_label(H, W, kFusionOutside);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      if (!on_surface(y, x)) continue;
      int l = labels[(y / p) * patches_across + x / p];
      if (!std::isfinite(cost[l](y, x))) {
        l = -1;
        for (int v = 0; v < n; ++v)
          if (std::isfinite(cost[v](y, x)) && (l < 0 || cost[v](y, x) < cost[l](y, x))) l = v;
      }
      pixel_label(y, x) = l < 0 ? kFusionUnseen : uchar(l);
    }
  cv::Mat3f acc(H, W, cv::Vec3f(0, 0, 0));
  cv::Mat1f wsum(H, W, 0.0f);
  for (int v = 0; v < n; ++v) {
    const cv::Mat1b mine = pixel_label == v;
    if (cv::countNonZero(mine) == 0) continue;
    cv::Mat1f w;
    mine.convertTo(w, CV_32F, 1 / 255.0);
    if (o.blend_sigma > 0) cv::GaussianBlur(w, w, cv::Size(0, 0), o.blend_sigma);
    w.setTo(0, ~r[v].Valid());
    cv::Mat3f c;
    r[v].colour.convertTo(c, CV_32F);
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x)
        if (w(y, x) > 0) {
          acc(y, x) += c(y, x) * w(y, x);
          wsum(y, x) += w(y, x);
        }
  }
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const uchar l = pixel_label(y, x);
      if (l >= n) continue;
      out->seen(y, x) = 255;
      out->minified(y, x) = r[l].minified(y, x);
      out->image(y, x) = wsum(y, x) > 1e-4f ? cv::Vec3b(acc(y, x) / wsum(y, x)) : r[l].colour(y, x);
    }
  out->label = pixel_label;
}

}  // namespace

FusedTexture FuseTexture(const FusionSurface& s, const std::vector<FusionView>& views,
                         const FusionOptions& o) {
  StepTimer timer;
  const int W = s.width, H = s.height;
  FusedTexture out;
  out.image = cv::Mat3b(H, W, cv::Vec3b(0, 0, 0));
  out.label = cv::Mat1b(H, W, kFusionOutside);
  out.seen = cv::Mat1b(H, W, uchar(0));
  out.minified = cv::Mat1b(H, W, uchar(0));
  std::vector<Eigen::Vector3d> screen(s.pixel.size());
  for (size_t i = 0; i < s.pixel.size(); ++i) screen[i] = {s.pixel[i].x(), s.pixel[i].y(), 1.0};
  const RasterResult raster = Rasterize(screen, s.triangles, W, H);
  const cv::Mat1b on_surface = raster.face >= 0;
  out.surface_pixels = cv::countNonZero(on_surface);
  out.label.setTo(kFusionUnseen, on_surface);
  if (views.empty() || views[0].photo.empty() || out.surface_pixels == 0) {
    out.unseen = out.surface_pixels > 0 ? 1 : 0;
    return out;
  }
  const std::vector<Eigen::Matrix<double, 3, 2>> dx_dpix =
      SurfacePerOutputPixel(s.world, s.pixel, s.triangles, 1.0);
  // The printed side: the way round the reference sees most of the surface.
  double positive = 0, negative = 0;
  for (double a : SignedAreas(s, views[0].camera)) (a > 0 ? positive : negative) += std::abs(a);
  const double printed_sign = positive >= negative ? 1 : -1;
  Eigen::Vector3d lo = s.world[0], hi = lo;
  for (const auto& v : s.world) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double depth_tolerance = 0.005 * (hi - lo).norm();

  std::vector<int> used;  // indices into `views`
  std::vector<ViewRendering> r;
  for (size_t v = 0; v < views.size(); ++v) {
    if (views[v].photo.empty()) continue;
    r.push_back(
        RenderView(s, raster, dx_dpix, views[v], printed_sign, depth_tolerance, o.antialias));
    used.push_back(int(v));
    FusionViewReport rep;
    rep.name = views[v].name;
    rep.seen = cv::countNonZero(r.back().Valid()) / double(out.surface_pixels);
    out.views.push_back(rep);
  }
  const int n = int(r.size());
  timer.Mark("fusion_render");
  fusion_internal::LevelAndRegister(o, &r, &out.views);
  timer.Mark("fusion_level_register");
  const std::vector<double> sharpness =
      fusion_internal::RelativeSharpness(o, r, out.surface_pixels);
  for (int v = 0; v < n; ++v) out.views[v].sharpness = sharpness[v];
  const std::vector<cv::Mat1f> cost = DataCosts(o, r, sharpness, on_surface);
  timer.Mark("fusion_costs");
  int patches_across = 0;
  const std::vector<int> labels = PatchLabels(o, r, cost, &patches_across);
  timer.Mark("fusion_labels");
  Blend(o, r, cost, labels, patches_across, on_surface, &out);

  long unseen = 0;
  std::vector<long> counts(n, 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const uchar l = out.label(y, x);
      if (l == kFusionUnseen) ++unseen;
      if (l < n) ++counts[l];
    }
  out.unseen = unseen / double(out.surface_pixels);
  for (int v = 0; v < n; ++v) out.views[v].share = counts[v] / double(out.surface_pixels);
  // Labels are indices into `views` (skipped views have none).
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (out.label(y, x) < n) out.label(y, x) = uchar(used[out.label(y, x)]);
  timer.Mark("fusion_blend");
  out.timings = timer.steps();
  return out;
}

cv::Vec3b LabelColour(int view) {
  // Distinct colours (BGR) for the first views; more repeat.
  static const cv::Vec3b kColours[] = {{180, 119, 31},  {14, 127, 255},  {44, 160, 44},
                                       {40, 39, 214},   {189, 103, 148}, {75, 86, 140},
                                       {194, 119, 227}, {34, 189, 188}};
  return kColours[view % 8];
}

cv::Mat3b DrawLabels(const cv::Mat1b& label) {
  cv::Mat3b out(label.size(), cv::Vec3b(0, 0, 0));
  for (int y = 0; y < label.rows; ++y)
    for (int x = 0; x < label.cols; ++x) {
      const uchar l = label(y, x);
      if (l == kFusionOutside) continue;
      out(y, x) = l == kFusionUnseen ? cv::Vec3b(128, 128, 128) : LabelColour(l);
    }
  return out;
}

}  // namespace docunfold
