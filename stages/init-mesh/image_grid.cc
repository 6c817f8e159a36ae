#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "common/errors.h"
#include "common/program.h"
#include "stages/init-mesh/init_mesh_internal.h"

namespace docunfold::init_mesh {
namespace {

double Length(const std::vector<Eigen::Vector2d>& p) {
  double l = 0;
  for (size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
  return l;
}

// n points along a polyline, equally spaced in arc length on the page (the
// polyline lifted to 3D), so quads are near-uniform on the page rather than
// in the perspective image. Also returns the 3D length.
std::vector<Eigen::Vector2d> ResampleOnPage(const std::vector<Eigen::Vector2d>& poly, int n,
                                            const Lift& lift, double* length3d) {
  const std::vector<Eigen::Vector2d> dense = Densify(poly, 3.0);
  std::vector<double> s{0};
  Eigen::Vector3d prev = lift(dense[0]);
  for (size_t i = 1; i < dense.size(); ++i) {
    const Eigen::Vector3d x = lift(dense[i]);
    s.push_back(s.back() + (x - prev).norm());
    prev = x;
  }
  *length3d = s.back();
  return AtEqualArcLength(dense, s, n);
}

// Signed area of quad q in the image (y down: positive for our orientation).
double QuadArea(const ImageGrid& g, int q) {
  const auto c = g.grid.Quad(q);
  double a = 0;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d& p = g.pixels[c[k]];
    const Eigen::Vector2d& n = g.pixels[c[(k + 1) % 4]];
    a += p.x() * n.y() - p.y() * n.x();
  }
  return a / 2;
}

// The four sides of the boundary, each running from its first corner to
// its second (top TL→TR, right TR→BR, bottom BL→BR, left TL→BL; a side drawn
// the other way round is turned); false (and why) when a side is too short
// or does not meet its corners.
bool SidesForPatch(const Boundary& b, std::array<std::vector<Eigen::Vector2d>, 4>* sides,
                   std::string* why) {
  std::array<std::vector<Eigen::Vector2d>, 4>& side = *sides;
  for (int s = 0; s < 4; ++s) {
    side[s] = b.sides[s].points;
    if (Length(side[s]) < 5) {
      *why = std::string("the ") + kSideNames[s] + " side is too short (under 5 px)";
      return false;
    }
  }
  const std::array<Eigen::Vector2d, 4>& corner = b.corners;  // TL, TR, BR, BL
  const std::array<std::array<int, 2>, 4> ends = {{{0, 1}, {1, 2}, {3, 2}, {0, 3}}};
  double mean_length = 0;
  for (int s = 0; s < 4; ++s) {
    const Eigen::Vector2d &a = corner[ends[s][0]], &z = corner[ends[s][1]];
    if ((side[s].front() - a).norm() + (side[s].back() - z).norm() >
        (side[s].back() - a).norm() + (side[s].front() - z).norm())
      std::reverse(side[s].begin(), side[s].end());
    mean_length += Length(side[s]) / 4;
  }
  for (int s = 0; s < 4; ++s) {
    const double gap = std::max((side[s].front() - corner[ends[s][0]]).norm(),
                                (side[s].back() - corner[ends[s][1]]).norm());
    if (gap > 0.1 * mean_length) {
      *why = std::string("the ") + kSideNames[s] + " side does not meet its corners (gap " +
             Fixed(gap, 0) + " px)";
      return false;
    }
  }
  return true;
}

// The Coons patch of the four sides (as SidesForPatch gives them), each
// resampled by arc length on the page; the grid's long side along the page's.
ImageGrid PatchOfSides(const std::array<std::vector<Eigen::Vector2d>, 4>& side,
                       const GridQuads& quads, const Lift& lift) {
  double len[4];
  const int n_dummy = 2;
  for (int s = 0; s < 4; ++s) ResampleOnPage(side[s], n_dummy, lift, &len[s]);
  const bool wide = len[0] + len[2] >= len[1] + len[3];
  const int nx = (wide ? quads.long_side : quads.short_side) + 1;
  const int ny = (wide ? quads.short_side : quads.long_side) + 1;
  std::array<std::vector<Eigen::Vector2d>, 4> s;
  for (int k = 0; k < 4; ++k) s[k] = ResampleOnPage(side[k], k % 2 == 0 ? nx : ny, lift, &len[k]);
  const Eigen::Vector2d tl = (s[0].front() + s[3].front()) / 2,
                        tr = (s[0].back() + s[1].front()) / 2;
  const Eigen::Vector2d br = (s[2].back() + s[1].back()) / 2, bl = (s[2].front() + s[3].back()) / 2;
  ImageGrid g;
  g.grid = {nx, ny};
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      const double u = double(c) / (nx - 1), v = double(r) / (ny - 1);
      g.pixels.push_back(
          (1 - v) * s[0][c] + v * s[2][c] + (1 - u) * s[3][r] + u * s[1][r] -
          ((1 - u) * (1 - v) * tl + u * (1 - v) * tr + (1 - u) * v * bl + u * v * br));
    }
  return g;
}

// A wiggly side (segmentation noise) can fold a few quads of the patch:
// relaxes the interior (each vertex toward the mean of its four neighbours,
// border fixed) until it unfolds. Returns the quads still folded (0: every
// quad has the same orientation).
int UnfoldPatch(ImageGrid* patch) {
  ImageGrid& g = *patch;
  const int nx = g.grid.nx, ny = g.grid.ny;
  auto count_flipped = [&] {
    int n = 0;
    for (int q = 0; q < g.grid.NumQuads(); ++q) n += QuadArea(g, q) <= 0;
    return n;
  };
  int flipped = count_flipped();
  for (int round = 0; flipped > 0 && round < 20; ++round) {
    for (int sweep = 0; sweep < 10; ++sweep) {
      std::vector<Eigen::Vector2d> next = g.pixels;
      for (int r = 1; r + 1 < ny; ++r)
        for (int c = 1; c + 1 < nx; ++c)
          next[g.grid.Index(r, c)] =
              0.25 * (g.pixels[g.grid.Index(r - 1, c)] + g.pixels[g.grid.Index(r + 1, c)] +
                      g.pixels[g.grid.Index(r, c - 1)] + g.pixels[g.grid.Index(r, c + 1)]);
      g.pixels = std::move(next);
    }
    flipped = count_flipped();
  }
  return flipped;
}

}  // namespace

std::vector<Eigen::Vector2d> AtEqualArcLength(const std::vector<Eigen::Vector2d>& points,
                                              const std::vector<double>& arc, int n) {
  std::vector<Eigen::Vector2d> out;
  size_t j = 0;
  for (int k = 0; k < n; ++k) {
    const double target = arc.back() * k / (n - 1);
    while (j + 2 < arc.size() && arc[j + 1] < target) ++j;
    const double span = arc[j + 1] - arc[j];
    const double f = span > 0 ? std::clamp((target - arc[j]) / span, 0.0, 1.0) : 0.0;
    out.push_back(points[j] + f * (points[j + 1] - points[j]));
  }
  return out;
}

std::vector<Eigen::Vector2d> Densify(const std::vector<Eigen::Vector2d>& p, double step) {
  std::vector<Eigen::Vector2d> out{p.front()};
  for (size_t i = 1; i < p.size(); ++i) {
    const int n = std::max(1, int(std::ceil((p[i] - p[i - 1]).norm() / step)));
    for (int k = 1; k <= n; ++k) out.push_back(p[i - 1] + (p[i] - p[i - 1]) * (double(k) / n));
  }
  return out;
}

bool CoonsGrid(const Boundary& b, const GridQuads& quads, const Lift& lift, const cv::Mat1b& region,
               ImageGrid* out, std::string* why) {
  std::array<std::vector<Eigen::Vector2d>, 4> side;
  if (!SidesForPatch(b, &side, why)) return false;
  ImageGrid g = PatchOfSides(side, quads, lift);
  // The patch must be a proper grid: every quad the same orientation, and on
  // the page.
  const int flipped = UnfoldPatch(&g);
  int inside = 0;
  for (const auto& p : g.pixels) {
    const int x = int(std::lround(p.x())), y = int(std::lround(p.y()));
    inside += x >= 0 && y >= 0 && x < region.cols && y < region.rows && region(y, x);
  }
  if (flipped > 0) {
    *why = "the Coons patch of the sides folds over (" + std::to_string(flipped) + " quads)";
    return false;
  }
  if (inside < 0.8 * g.pixels.size()) {
    *why = "the Coons patch of the sides lies mostly outside mask.png";
    return false;
  }
  *out = std::move(g);
  return true;
}

ImageGrid BoundingBoxGrid(const cv::Mat1b& mask, const GridQuads& quads, const Lift& lift) {
  const cv::Rect box = cv::boundingRect(mask);
  const Eigen::Vector2d p0(box.x, box.y), p1(box.x + box.width - 1, box.y + box.height - 1);
  const double wide3d = (lift(Eigen::Vector2d(p1.x(), p0.y())) - lift(p0)).norm() +
                        (lift(p1) - lift(Eigen::Vector2d(p0.x(), p1.y()))).norm();
  const double tall3d = (lift(Eigen::Vector2d(p0.x(), p1.y())) - lift(p0)).norm() +
                        (lift(p1) - lift(Eigen::Vector2d(p1.x(), p0.y()))).norm();
  const bool wide = wide3d >= tall3d;
  ImageGrid g;
  g.grid = {(wide ? quads.long_side : quads.short_side) + 1,
            (wide ? quads.short_side : quads.long_side) + 1};
  for (int r = 0; r < g.grid.ny; ++r)
    for (int c = 0; c < g.grid.nx; ++c)
      g.pixels.push_back(p0 + Eigen::Vector2d((p1.x() - p0.x()) * c / (g.grid.nx - 1),
                                              (p1.y() - p0.y()) * r / (g.grid.ny - 1)));
  return g;
}

std::string CheckCoverage(const ImageGrid& g, const std::vector<Eigen::Vector2d>& pixels, int width,
                          int height, const Options& o, const std::string& image) {
  cv::Mat1i label(height, width, -1);
  for (int q = 0; q < g.grid.NumQuads(); ++q) {
    const auto c = g.grid.Quad(q);
    std::vector<cv::Point> poly;
    for (int k = 0; k < 4; ++k)
      poly.emplace_back(int(std::lround(g.pixels[c[k]].x())), int(std::lround(g.pixels[c[k]].y())));
    cv::fillPoly(label, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(q));
  }
  int count[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};  // [row third][column third]
  for (const auto& p : pixels) {
    const int x = int(std::lround(p.x())), y = int(std::lround(p.y()));
    if (x < 0 || y < 0 || x >= width || y >= height || label(y, x) < 0) continue;
    const int q = label(y, x), qr = q / (g.grid.nx - 1), qc = q % (g.grid.nx - 1);
    ++count[std::min(2, 3 * qr / (g.grid.ny - 1))][std::min(2, 3 * qc / (g.grid.nx - 1))];
  }
  int covered = 0;
  for (const auto& row : count)
    for (const int n : row) covered += n >= o.min_points_per_ninth;
  const int left = count[0][0] + count[1][0] + count[2][0];
  const int right = count[0][2] + count[1][2] + count[2][2];
  const int top = count[0][0] + count[0][1] + count[0][2];
  const int bottom = count[2][0] + count[2][1] + count[2][2];
  const std::pair<const char*, int> parts[4] = {
      {"left", left}, {"right", right}, {"top", top}, {"bottom", bottom}};
  std::string empty;
  for (const auto& [name, n] : parts)
    if (n < o.min_points_per_ninth) empty += std::string(empty.empty() ? "" : ", ") + name;
  if (covered < o.min_covered_ninths)
    throw InputError("points cover only " + std::to_string(covered) + " of the page's 9 parts in " +
                     image + " (need " + std::to_string(o.min_covered_ninths) + "; " +
                     std::to_string(pixels.size()) + " points inside the document region" +
                     (empty.empty() ? std::string() : ", none in the " + empty + " third") +
                     "): the page cannot be reconstructed");
  if (empty.empty()) return "";
  return "no points in the " + empty + " third of the page in " + image +
         ": its shape there is carried over from the rest";
}

}  // namespace docunfold::init_mesh
