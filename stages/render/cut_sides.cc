#include "stages/render/cut_sides.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "common/raster.h"
#include "common/statistics.h"
#include "common/texture_sampler.h"

namespace docunfold::render {

namespace {

// Outward normal of side i of M' (y down): top, right, bottom, left.
Eigen::Vector2d Outward(int side) {
  static const Eigen::Vector2d n[4] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};
  return n[side];
}

// The grid's border b (0 first row, 1 last column, 2 last row, 3 first
// column): its vertices in order and, for each, the vertex `depth` steps
// inwards.
struct Border {
  std::vector<int> vertex;
  std::vector<int> inner;
};

Border GridBorder(const QuadGrid& g, int b, int depth) {
  Border border;
  const bool along_row = b == 0 || b == 2;
  const int n = along_row ? g.nx : g.ny;
  for (int k = 0; k < n; ++k) {
    switch (b) {
      case 0:
        border.vertex.push_back(g.Index(0, k));
        border.inner.push_back(g.Index(depth, k));
        break;
      case 1:
        border.vertex.push_back(g.Index(k, g.nx - 1));
        border.inner.push_back(g.Index(k, g.nx - 1 - depth));
        break;
      case 2:
        border.vertex.push_back(g.Index(g.ny - 1, k));
        border.inner.push_back(g.Index(g.ny - 1 - depth, k));
        break;
      default:
        border.vertex.push_back(g.Index(k, 0));
        border.inner.push_back(g.Index(k, depth));
        break;
    }
  }
  return border;
}

// The grid border lying farthest out on the side of M' whose outward
// normal is `n`.
int OutermostBorder(const QuadGrid& g, const std::vector<Eigen::Vector2d>& flat,
                    const Eigen::Vector2d& n) {
  int best = 0;
  double best_out = -1e300;
  for (int b = 0; b < 4; ++b) {
    const Border border = GridBorder(g, b, 0);
    double sum = 0;
    for (int v : border.vertex) sum += n.dot(flat[v]);
    if (sum / border.vertex.size() > best_out) {
      best_out = sum / border.vertex.size();
      best = b;
    }
  }
  return best;
}

// What the views see along the surface continued out from each column of
// a border.
struct BorderScan {
  std::vector<double> crossings;  // where a view sees the page edge (the bound's coordinate)
  std::vector<double> seen_page;  // per column: the farthest page seen
  // Per border column: the continuation's direction (per step of t).
  std::vector<Eigen::Vector3d> dir3;
  std::vector<Eigen::Vector2d> dir2;
  // Per view: its crossings, and the |cos| between its ray and the
  // continued surface's normal at each.
  std::vector<std::vector<double>> view_crossings, view_cos;
};

// Continues the surface out from every column of `border` (its inner
// vertices `depth` steps inwards) past side `side`, up to
// options.max_extension times `extent`, and follows it in every view's page
// mask: where it leaves the page (a crossing) or how far the view sees page.
BorderScan ScanBorder(const MeshPair& meshes, const std::vector<Eigen::Vector2d>& flat,
                      const Border& border, int depth, int side, double extent,
                      const std::vector<ViewMask>& views, const CutSideOptions& options) {
  const Eigen::Vector2d n = Outward(side);
  const bool vertical_axis = side == 0 || side == 2;  // the bound is a y
  constexpr int kStepsPerExtent = 400;
  BorderScan scan;
  std::vector<double>& crossings = scan.crossings;
  std::vector<double>& seen_page = scan.seen_page;
  std::vector<Eigen::Vector3d>& dir3 = scan.dir3;
  std::vector<Eigen::Vector2d>& dir2 = scan.dir2;
  dir3.assign(border.vertex.size(), Eigen::Vector3d::Zero());
  dir2.assign(border.vertex.size(), Eigen::Vector2d::Zero());
  scan.view_crossings.assign(views.size(), {});
  scan.view_cos.assign(views.size(), {});
  for (size_t k = 0; k < border.vertex.size(); ++k) {
    const int vb = border.vertex[k], vi = border.inner[k];
    const Eigen::Vector3d d3 = (meshes.mesh3d[vb] - meshes.mesh3d[vi]) / depth;
    const Eigen::Vector2d d2 = (flat[vb] - flat[vi]) / depth;
    const double speed = n.dot(d2);  // outward M' distance per step of t
    if (!(speed > 0)) continue;
    // The continued surface's normal: across the border and along it.
    const Eigen::Vector3d along =
        meshes.mesh3d[border.vertex[std::min(k + 1, border.vertex.size() - 1)]] -
        meshes.mesh3d[border.vertex[k > 0 ? k - 1 : 0]];
    const Eigen::Vector3d normal = d3.cross(along).normalized();
    dir3[k] = d3;
    dir2[k] = d2;
    const double dt = extent / (kStepsPerExtent * speed);
    const int steps = int(std::ceil(options.max_extension * kStepsPerExtent));
    double column_seen = std::nan("");  // farthest page any view sees here
    for (size_t v = 0; v < views.size(); ++v) {
      const ViewMask& view = views[v];
      const double m = options.frame_margin * std::hypot(view.camera.width, view.camera.height);
      // -1 unseen (behind the camera or off the photo), 0 table, 1 page.
      auto state_at = [&](int j, Eigen::Vector2d* px) {
        const auto projected =
            ProjectDistorted(view.camera, view.distortion, meshes.mesh3d[vb] + j * dt * d3);
        if (!projected) return -1;
        *px = *projected;
        if (!(px->x() >= m && px->y() >= m && px->x() <= view.camera.width - 1 - m &&
              px->y() <= view.camera.height - 1 - m))
          return -1;
        return view.mask(int(std::lround(px->y())), int(std::lround(px->x()))) ? 1 : 0;
      };
      // Out from the border for as long as the view sees page there.
      Eigen::Vector2d px;
      if (state_at(0, &px) != 1) continue;
      int last_page = 0;
      for (int j = 1; j <= steps; ++j) {
        const int state = state_at(j, &px);
        if (state == 1) {
          last_page = j;
          continue;
        }
        if (state == -1) break;  // off the photo: page at least to last_page
        // Table from here on for confirm_px in the photo: a notch in the
        // mask or a dark print blob is not the page edge.
        int l = j + 1, ahead = 0;
        Eigen::Vector2d px_ahead = px;
        for (; l <= steps && (px_ahead - px).norm() < options.confirm_px; ++l)
          if ((ahead = state_at(l, &px_ahead)) != 0) break;
        if (ahead == 0 && (px_ahead - px).norm() >= options.confirm_px) {
          const Eigen::Vector2d q = flat[vb] + (j - 0.5) * dt * d2;
          crossings.push_back(vertical_axis ? q.y() : q.x());
          const Eigen::Vector3d ray =
              (meshes.mesh3d[vb] + (j - 0.5) * dt * d3 - view.camera.Center()).normalized();
          scan.view_crossings[v].push_back(crossings.back());
          scan.view_cos[v].push_back(std::abs(normal.dot(ray)));
          last_page = 0;  // the edge says more than a lower bound
          break;
        }
        if (ahead != 1) break;
        last_page = j = l;
      }
      if (last_page > 0) {
        const Eigen::Vector2d q = flat[vb] + last_page * dt * d2;
        const double c = vertical_axis ? q.y() : q.x();
        column_seen = std::isnan(column_seen)  ? c
                      : side == 0 || side == 3 ? std::min(column_seen, c)
                                               : std::max(column_seen, c);
      }
    }
    if (!std::isnan(column_seen)) seen_page.push_back(column_seen);
  }
  return scan;
}

// The surface continued past side `side` from every column of `border` up
// to the line of edge->bound in M' (edge->strip).
void BuildStrip(const MeshPair& meshes, const std::vector<Eigen::Vector2d>& flat,
                const Border& border, int depth, int side, const BorderScan& scan,
                const CutSideOptions& options, CutSideEdge* edge_out) {
  const Eigen::Vector2d n = Outward(side);
  const CutSideEdge& edge = *edge_out;
  const std::vector<Eigen::Vector3d>& dir3 = scan.dir3;
  const std::vector<Eigen::Vector2d>& dir2 = scan.dir2;
  // Each column continues until it reaches the bound's line in M'.
  ExtensionStrip& strip = edge_out->strip;
  strip.cols = int(border.vertex.size());
  const int band = std::max(0, options.band_rows);
  strip.rows = band + std::max(2, options.strip_rows);
  strip.mesh3d.resize(size_t(strip.cols) * strip.rows);
  strip.flat.resize(strip.mesh3d.size());
  const double target = (side == 0 || side == 3) ? -edge.bound : edge.bound;
  for (int k = 0; k < strip.cols; ++k) {
    const int vb = border.vertex[k];
    const double speed = n.dot(dir2[k]);
    const double t_end = speed > 0 ? std::max(0.0, (target - n.dot(flat[vb])) / speed) : 0;
    for (int j = 0; j < strip.rows; ++j) {
      // Band rows run back over the mesh, towards the inner vertex.
      const double t = j < band ? -double(depth) * (band - j) / band
                                : t_end * (j - band) / (strip.rows - band - 1);
      strip.mesh3d[size_t(j) * strip.cols + k] = meshes.mesh3d[vb] + t * dir3[k];
      strip.flat[size_t(j) * strip.cols + k] = flat[vb] + t * dir2[k];
    }
  }
}

// CutSideOptions::squarest_view: edge->bound from the view whose rays meet
// the continued surface most squarely where they cross the page edge, or
// from views[0]'s (the reference's) where that view's bound lies too far
// from it. False when views[0] has too few crossings.
bool SquarestViewBound(const BorderScan& scan, const std::vector<ViewMask>& views, double extent,
                       const CutSideOptions& options, CutSideEdge* edge) {
  const auto& crossings = scan.view_crossings;
  if (crossings.empty() || int(crossings[0].size()) < options.min_crossings) return false;
  const double reference_bound = Median(crossings[0]);
  int best = 0;
  double best_cos = Median(scan.view_cos[0]);
  for (size_t v = 1; v < crossings.size(); ++v) {
    // A view that sees the edge along less than half of what the
    // reference sees of it gives the median of another stretch of the side.
    if (int(crossings[v].size()) < std::max(options.min_crossings, int(crossings[0].size()) / 2))
      continue;
    const double cos = Median(scan.view_cos[v]);
    if (!(AlongSurface(cos) < AlongSurface(best_cos))) continue;
    if (std::abs(Median(crossings[v]) - reference_bound) > options.max_view_disagreement * extent)
      continue;
    best = int(v);
    best_cos = cos;
  }
  edge->bound = Median(crossings[size_t(best)]);
  edge->edge_seen = true;
  if (best > 0) edge->placed_by = views[size_t(best)].camera.image;
  edge->placed_by_cos = best_cos;
  return true;
}

}  // namespace

double AlongSurface(double c) { return std::sqrt(std::max(0.0, 1 - c * c)) / std::max(c, 1e-9); }

std::array<CutSideEdge, 4> FindCutSideEdges(const MeshPair& meshes,
                                            const std::vector<Eigen::Vector2d>& flat,
                                            const Eigen::Vector4d& visible_box,
                                            const std::array<bool, 4>& cut,
                                            const std::vector<ViewMask>& views,
                                            const CutSideOptions& options) {
  std::array<CutSideEdge, 4> edges;
  const QuadGrid& g = meshes.grid;
  if (g.nx < 3 || g.ny < 3) return edges;
  for (int side = 0; side < 4; ++side) {
    CutSideEdge& edge = edges[side];
    if (!cut[side]) continue;
    if (views.empty()) {
      edge.note = "no other view's page mask";
      continue;
    }
    const Eigen::Vector2d n = Outward(side);
    const bool vertical_axis = side == 0 || side == 2;  // the bound is a y
    const double extent =
        vertical_axis ? visible_box[3] - visible_box[1] : visible_box[2] - visible_box[0];
    const int best = OutermostBorder(g, flat, n);
    const int rows_inward = (best == 0 || best == 2) ? g.ny - 1 : g.nx - 1;
    const int depth =
        std::clamp(int(std::lround(options.base_fraction * rows_inward)), 1, rows_inward);
    const Border border = GridBorder(g, best, depth);
    const BorderScan scan = ScanBorder(meshes, flat, border, depth, side, extent, views, options);
    const std::vector<double>& crossings = scan.crossings;
    const std::vector<double>& seen_page = scan.seen_page;
    edge.crossings = int(crossings.size());
    edge.columns_seen = int(seen_page.size());
    edge.views = int(std::count_if(scan.view_crossings.begin(), scan.view_crossings.end(),
                                   [](const auto& c) { return !c.empty(); }));
    if (options.squarest_view) {
      if (!SquarestViewBound(scan, views, extent, options, &edge)) {
        edge.note =
            "the reference's own outline does not cross the continued surface (" +
            std::to_string(scan.view_crossings.empty() ? 0 : scan.view_crossings[0].size()) +
            " crossings; " + std::to_string(options.min_crossings) + " needed)";
        continue;
      }
    } else if (edge.crossings >= options.min_crossings) {
      edge.bound = Median(crossings);
      edge.edge_seen = true;
    } else if (edge.columns_seen >= options.min_crossings) {
      // No photo sees the edge itself; the page reaches at least as far as
      // the photos see it (a high quantile over the columns: the page is a
      // rectangle, so page seen past any column is page past the side).
      edge.bound = Quantile(
          seen_page, side == 0 || side == 3 ? 1 - options.seen_quantile : options.seen_quantile);
    } else {
      edge.note =
          "the other views see neither the page edge nor page past this side "
          "(" +
          std::to_string(edge.crossings) + " crossings, " + std::to_string(edge.columns_seen) +
          " columns seen; " + std::to_string(options.min_crossings) + " needed)";
      continue;
    }
    const double visible_bound = visible_box[BoxIndexOfSide(side)];
    const double sign = (side == 0 || side == 3) ? -1 : 1;
    edge.extension = sign * (edge.bound - visible_bound);
    if (edge.extension < 0) {
      edge.bound = visible_bound;
      edge.extension = 0;
    }
    edge.measured = true;
    if (edge.extension > 0) BuildStrip(meshes, flat, border, depth, side, scan, options, &edge);
  }
  return edges;
}

namespace {

// Least agreement (Agreement()) with the reference for a view to be used.
constexpr double kMinAgreement = 0.3;

struct StripMesh {
  std::vector<Eigen::Vector3d> screen, world;
  std::vector<Triangle> triangles;
};

StripMesh JoinStrips(const std::vector<const ExtensionStrip*>& strips, const PixelFrame& frame) {
  StripMesh m;
  for (const ExtensionStrip* strip : strips) {
    const int base = int(m.screen.size());
    for (size_t i = 0; i < strip->flat.size(); ++i) {
      const Eigen::Vector2d px = frame.ToPixel(strip->flat[i]);
      m.screen.emplace_back(px.x(), px.y(), 1.0);
      m.world.push_back(strip->mesh3d[i]);
    }
    for (int j = 0; j + 1 < strip->rows; ++j)
      for (int k = 0; k + 1 < strip->cols; ++k) {
        const int a = base + j * strip->cols + k, b = a + 1, c = a + strip->cols + 1,
                  d = a + strip->cols;
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({a, c, d});
      }
  }
  return m;
}

// One view's rendering of the strips: colour, and per pixel the view's
// pixels per output pixel (0 where the view does not show the strip).
struct ViewRendering {
  cv::Mat3b colour;
  cv::Mat1f density;
};

ViewRendering RenderStripsFromView(const StripMesh& m, const ViewMask& view,
                                   const TextureSampler& sampler, int width, int height,
                                   bool antialias) {
  const std::vector<Eigen::Vector3d>& screen = m.screen;
  const RasterResult raster = Rasterize(screen, m.triangles, width, height);
  // Per triangle: all corners on the view's page mask, and the affine map
  // output pixel -> view pixel (the footprint).
  std::vector<char> usable(m.triangles.size(), 0);
  std::vector<Eigen::Matrix2d> jacobian(m.triangles.size());
  for (size_t f = 0; f < m.triangles.size(); ++f) {
    const Triangle& t = m.triangles[f];
    Eigen::Matrix2d S;
    S << (screen[t[1]] - screen[t[0]]).head<2>(), (screen[t[2]] - screen[t[0]]).head<2>();
    if (!(std::abs(S.determinant()) > 1e-9)) continue;
    Eigen::Vector2d px[3];
    bool ok = true;
    for (int c = 0; c < 3 && ok; ++c) {
      const auto projected = ProjectDistorted(view.camera, view.distortion, m.world[t[c]]);
      if (projected) px[c] = *projected;
      ok = projected && px[c].x() >= 0 && px[c].y() >= 0 && px[c].x() <= view.camera.width - 1 &&
           px[c].y() <= view.camera.height - 1 &&
           view.mask(int(std::lround(px[c].y())), int(std::lround(px[c].x())));
    }
    if (!ok) continue;
    Eigen::Matrix2d P;
    P << px[1] - px[0], px[2] - px[0];
    usable[f] = 1;
    jacobian[f] = P * S.inverse();
  }
  ViewRendering out{cv::Mat3b(height, width, cv::Vec3b(0, 0, 0)), cv::Mat1f(height, width, 0.0f)};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int f = raster.face(y, x);
      if (f < 0 || !usable[f]) continue;
      const Triangle& t = m.triangles[f];
      const cv::Vec2f b = raster.bary(y, x);
      const Eigen::Vector3d p =
          (1 - b[0] - b[1]) * m.world[t[0]] + b[0] * m.world[t[1]] + b[1] * m.world[t[2]];
      const auto projected = ProjectDistorted(view.camera, view.distortion, p);
      if (!projected) continue;
      const Eigen::Vector2d px = *projected;
      const Eigen::Matrix2d& J = jacobian[f];
      const float Jf[4] = {float(J(0, 0)), float(J(0, 1)), float(J(1, 0)), float(J(1, 1))};
      float colour[3];
      sampler.Sample(float(px.x()), float(px.y()), Jf, antialias, colour);
      out.colour(y, x) =
          cv::Vec3b(cv::saturate_cast<uchar>(colour[0]), cv::saturate_cast<uchar>(colour[1]),
                    cv::saturate_cast<uchar>(colour[2]));
      out.density(y, x) = float(std::sqrt(std::abs(J.determinant())));
    }
  }
  return out;
}

// Grey levels minus their blur: the fine detail (print) of a rendering.
cv::Mat1f FineDetail(const cv::Mat3b& image) {
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  cv::Mat1f f, low;
  grey.convertTo(f, CV_32F);
  cv::GaussianBlur(f, low, cv::Size(0, 0), 3);
  return f - low;
}

// The reference's rendering as every view is compared with it (computed
// once for all views).
struct ReferenceRendering {
  cv::Mat grey;         // 8-bit
  cv::Mat1f detail;     // FineDetail
  cv::Mat1b valid;      // where it shows the page
  cv::Mat1b keypoints;  // `valid` away from its border (SIFT's mask)
};

ReferenceRendering PrepareReference(const cv::Mat3b& image, const cv::Mat1b& valid) {
  ReferenceRendering r;
  cv::cvtColor(image, r.grey, cv::COLOR_BGR2GRAY);
  r.detail = FineDetail(image);
  r.valid = valid;
  cv::erode(valid, r.keypoints, cv::Mat(), cv::Point(-1, -1), 4);
  return r;
}

// The affine map (output pixels) that moves `view` onto the reference where
// both show the page: SIFT matches between the two renderings, RANSAC.
// Identity when fewer than `min_inliers` matches agree.
cv::Matx23d Register(const ReferenceRendering& reference, const ViewRendering& view,
                     int min_inliers, int* inliers) {
  *inliers = 0;
  const cv::Matx23d identity(1, 0, 0, 0, 1, 0);
  cv::Mat grey_view;
  cv::cvtColor(view.colour, grey_view, cv::COLOR_BGR2GRAY);
  cv::Mat1b view_valid = view.density > 0;
  // Keypoints away from the renderings' own borders.
  cv::Mat1b view_mask;
  cv::erode(view_valid, view_mask, cv::Mat(), cv::Point(-1, -1), 4);
  // Only near the overlap: the reference far from the strips says nothing.
  cv::Mat1b near_view;
  cv::dilate(view_valid, near_view, cv::Mat(), cv::Point(-1, -1), 40);
  const cv::Mat1b ref_mask = reference.keypoints & near_view;
  if (cv::countNonZero(ref_mask) < 100 || cv::countNonZero(view_mask) < 100) return identity;
  // SIFT on the box of the view's rendering and its surroundings only (its
  // pyramid over the whole output would cost most of render's time).
  const cv::Rect box = cv::boundingRect(near_view);
  const cv::Ptr<cv::SIFT> sift = cv::SIFT::create(4000);
  std::vector<cv::KeyPoint> kr, kv;
  cv::Mat dr, dv;
  sift->detectAndCompute(reference.grey(box), ref_mask(box), kr, dr);
  sift->detectAndCompute(grey_view(box), view_mask(box), kv, dv);
  if (kr.size() < size_t(min_inliers) || kv.size() < size_t(min_inliers)) return identity;
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(dv, dr, knn, 2);
  std::vector<cv::Point2f> from, to;
  for (const auto& m : knn)
    if (m.size() == 2 && m[0].distance < 0.8f * m[1].distance) {
      from.push_back(kv[m[0].queryIdx].pt + cv::Point2f(box.tl()));
      to.push_back(kr[m[0].trainIdx].pt + cv::Point2f(box.tl()));
    }
  if (from.size() < size_t(min_inliers)) return identity;
  std::vector<uchar> keep;
  const cv::Mat A = cv::estimateAffine2D(from, to, keep, cv::RANSAC, 3.0);
  *inliers = cv::countNonZero(keep);
  if (A.empty() || *inliers < min_inliers) return identity;
  return cv::Matx23d(A);
}

// `view` moved by the affine map A (output pixels).
ViewRendering Warp(const ViewRendering& view, const cv::Matx23d& A) {
  ViewRendering out;
  cv::warpAffine(view.colour, out.colour, A, view.colour.size(), cv::INTER_LINEAR);
  cv::warpAffine(view.density, out.density, A, view.density.size(), cv::INTER_NEAREST);
  // Bilinear colour at the rendering's edge mixes in the empty black.
  cv::Mat1b inside = out.density > 0;
  cv::erode(inside, inside, cv::Mat());
  out.density.setTo(0, ~inside);
  return out;
}

// How well `view` matches the reference where both show the page: the
// correlation of their fine detail, -1..1; 0 when they overlap in fewer than
// 500 pixels.
double Agreement(const ReferenceRendering& reference, const ViewRendering& view) {
  cv::Mat1b both = reference.valid & (view.density > 0);
  cv::erode(both, both, cv::Mat(), cv::Point(-1, -1), 3);
  if (cv::countNonZero(both) < 500) return 0;
  const cv::Mat1f& a = reference.detail;
  const cv::Mat1f b = FineDetail(view.colour);
  cv::Scalar ma, sa, mb, sb;
  cv::meanStdDev(a, ma, sa, both);
  cv::meanStdDev(b, mb, sb, both);
  const cv::Mat1f prod = (a - ma[0]).mul(b - mb[0]);
  return cv::mean(prod, both)[0] / (sa[0] * sb[0] + 1e-9);
}

// Moves view `v`'s rendering `r` onto the reference's where the two overlap
// when SIFT matches agree on an affine map that improves the correlation of
// their fine detail. A view that still correlates below kMinAgreement is
// not to be used: it would repeat or misplace what the reference shows.
ViewRegistration RegisterWithReference(const ReferenceRendering& reference, int v,
                                       ViewRendering* r) {
  ViewRegistration reg;
  reg.view = v;
  reg.agreement = Agreement(reference, *r);
  const cv::Matx23d A = Register(reference, *r, 15, &reg.inliers);
  if (reg.inliers >= 15) {
    ViewRendering moved = Warp(*r, A);
    const double agreement = Agreement(reference, moved);
    if (agreement > reg.agreement) {
      reg.affine = A;
      reg.agreement = agreement;
      reg.moved = true;
      *r = moved;
    }
  }
  reg.used = reg.agreement >= kMinAgreement;
  return reg;
}

}  // namespace

cv::Mat1b TextureStrips(const std::vector<const ExtensionStrip*>& strips,
                        const std::vector<ViewMask>& views, const std::vector<cv::Mat>& photos,
                        const PixelFrame& frame, bool antialias, const cv::Mat3b& reference_render,
                        const cv::Mat1b& reference_valid, const cv::Mat1b& fillable,
                        cv::Mat3b* image, std::vector<ViewRegistration>* registrations,
                        bool own_photo) {
  const int W = image->cols, H = image->rows;
  cv::Mat1b done(H, W, uchar(0));
  const StripMesh m = JoinStrips(strips, frame);
  if (m.triangles.empty()) return done;
  const ReferenceRendering reference = PrepareReference(reference_render, reference_valid);
  cv::Mat1f best(H, W, 0.0f);
  for (size_t v = 0; v < views.size(); ++v) {
    if (photos[v].empty()) continue;
    const TextureSampler sampler(photos[v]);
    ViewRendering r = RenderStripsFromView(m, views[v], sampler, W, H, antialias);
    if (cv::countNonZero(r.density > 0) == 0) continue;
    // The other view sees M where it is least sure (the page's cut edge in
    // the reference view); move its texture onto the reference's where the
    // two overlap (the strips' band rows run back over M). The reference's
    // own photo matches itself: nothing to register.
    ViewRegistration reg;
    reg.view = int(v);
    reg.used = true;
    if (!own_photo) reg = RegisterWithReference(reference, int(v), &r);
    if (registrations) registrations->push_back(reg);
    if (!reg.used) continue;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const float d = r.density(y, x);
        if (!fillable(y, x) || !(d > best(y, x))) continue;
        best(y, x) = d;
        (*image)(y, x) = r.colour(y, x);
        done(y, x) = 255;
      }
  }
  return done;
}

}  // namespace docunfold::render
