#include "stages/render/render.h"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/cli.h"
#include "common/errors.h"
#include "common/raster.h"
#include "common/statistics.h"
#include "stages/render/crop.h"
#include "stages/render/orientation.h"
#include "stages/render/texture_sampler.h"

namespace docunfold::render {
namespace {

using Clock = std::chrono::steady_clock;

// Output pixel states.
constexpr uchar kOutside = 0;        // not on M'
constexpr uchar kPage = 1;           // sampled from the reference image
constexpr uchar kHidden = 2;         // on M', but the reference view does not see it
constexpr uchar kOtherView = 4;      // past a cut side, from another view's photo
constexpr uchar kHiddenSampled = 3;  // the same, sampled anyway (--sample-hidden)

// Largest rms distance of a side's samples from its fitted line, as a
// fraction of the diagonal of M', for the side to bound the crop.
constexpr double kMaxSideRms = 0.005;

class StepTimer {
 public:
  explicit StepTimer(std::vector<std::pair<std::string, double>>* out) : out_(out) {}
  void Mark(const std::string& step) {
    const auto now = Clock::now();
    out_->emplace_back(step, std::chrono::duration<double>(now - last_).count());
    last_ = now;
  }

 private:
  std::vector<std::pair<std::string, double>>* out_;
  Clock::time_point last_ = Clock::now();
};

// "paper", "white" or "#RRGGBB" (BGR out); UsageError otherwise.
cv::Vec3b ParseFill(const std::string& fill, bool* paper) {
  *paper = fill == "paper";
  if (*paper) return {255, 255, 255};
  if (fill == "white") return {255, 255, 255};
  unsigned r, g, b;
  char tail;
  if (fill.size() == 7 && std::sscanf(fill.c_str(), "#%2x%2x%2x%c", &r, &g, &b, &tail) == 3)
    return {uchar(b), uchar(g), uchar(r)};
  throw UsageError("--fill: expected paper, white or #RRGGBB, got \"" + fill + "\"");
}

void CheckSizeOptions(const RenderOptions& o) {
  const int chosen = (o.width > 0) + (o.height > 0) + (o.dpi > 0) + (o.scale > 0);
  if (chosen > 1) throw UsageError("give at most one of --width, --height, --dpi, --scale");
  if (o.width < 0 || o.height < 0 || o.dpi < 0 || o.scale < 0 || o.page_width_mm < 0 ||
      o.page_height_mm < 0)
    throw UsageError("sizes must be positive");
  if (o.dpi > 0 && (o.page_width_mm > 0) == (o.page_height_mm > 0))
    throw UsageError(
        "--dpi needs exactly one of --page-width-mm, --page-height-mm "
        "(photos carry no absolute scale)");
  if (o.dpi == 0 && (o.page_width_mm > 0 || o.page_height_mm > 0))
    throw UsageError("--page-width-mm/--page-height-mm only make sense with --dpi");
  if (!(o.max_pixels >= 1)) throw UsageError("--max-pixels must be at least 1");
}

// Inputs that disagree with each other; names the file at fault.
void CheckInputs(const RenderInputs& in) {
  const PinholeCamera& cam = in.camera;
  if (in.reference.empty() || in.reference.type() != CV_8UC3)
    throw InputError(in.reference_file.string() + ": expected an 8-bit colour image");
  if (in.reference.cols != cam.width || in.reference.rows != cam.height)
    throw InputError(in.cameras_file.string() + ": reference camera " + cam.image + " is " +
                     std::to_string(cam.width) + "x" + std::to_string(cam.height) + " but " +
                     in.reference_file.filename().string() + " is " +
                     std::to_string(in.reference.cols) + "x" + std::to_string(in.reference.rows));
  if (in.boundary.width != in.reference.cols || in.boundary.height != in.reference.rows)
    throw InputError(in.boundary.file.string() + ": made for a " +
                     std::to_string(in.boundary.width) + "x" + std::to_string(in.boundary.height) +
                     " image but " + in.reference_file.filename().string() + " is " +
                     std::to_string(in.reference.cols) + "x" + std::to_string(in.reference.rows));
  const MeshPair& m = in.meshes;
  const fs::path m3 = in.meshes_dir / "mesh3d.ply", m2 = in.meshes_dir / "mesh2d.ply";
  if (m.grid.nx < 2 || m.grid.ny < 2 || int(m.mesh3d.size()) != m.grid.NumVertices() ||
      int(m.mesh2d.size()) != m.grid.NumVertices())
    throw InputError(m3.string() + ": not a grid of at least 2x2 vertices matching mesh2d.ply");
  int behind = 0;
  for (const Eigen::Vector3d& v : m.mesh3d)
    if (!(cam.CamFromWorld(v).z() > 0)) ++behind;
  if (behind > 0)
    throw InputError(m3.string() + ": " + std::to_string(behind) + " of " +
                     std::to_string(m.mesh3d.size()) +
                     " vertices lie behind the reference camera (depth <= 0)");
  Eigen::Vector2d lo = m.mesh2d[0], hi = lo;
  for (const auto& q : m.mesh2d) {
    if (!q.allFinite()) throw InputError(m2.string() + ": non-finite vertex");
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  if (!((hi - lo).minCoeff() > 0)) throw InputError(m2.string() + ": the flat mesh has no area");
}

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

struct ProjectedMesh {
  std::vector<Eigen::Vector3d> cam;    // vertices in the reference camera frame
  std::vector<Eigen::Vector2d> pixel;  // their projections
  std::vector<Triangle> triangles;
  std::vector<char> front;  // triangle faces the camera like most of M
  double density = 0;       // reference pixels per unit of M'
  int faces_in_view = 0;
};

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

struct SizeChoice {
  double scale = 0;  // output pixels per unit of M'
  int width = 0, height = 0;
  std::string rule;
  bool capped = false;
};

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

// The texture mapping proper: every output pixel's point of M' -> M ->
// reference pixel, sampled with the footprint of the pixel.
struct SampleStats {
  long page = 0, hidden = 0, minified = 0;
};

SampleStats SamplePixels(const RenderOptions& options, const RenderInputs& in,
                         const ProjectedMesh& pm, const std::vector<Eigen::Vector2d>& flat,
                         const RasterResult& out_raster, const RasterResult& ref_raster,
                         double scale, cv::Mat3b* image, cv::Mat1b* state) {
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
  // pixel is in front of it by more than this (DESIGN: tolerances relative to
  // the document size).
  const double depth_tolerance = 0.005 * diag;
  const TextureSampler sampler(in.reference);
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
                   const std::vector<Eigen::Vector2d>& flat, double x0, double y0, double scale,
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
      lengths.push_back((flat[g.Index(r, c + 1)] - flat[g.Index(r, c)]).norm() * scale);
  for (int r = 0; r + 1 < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c)
      lengths.push_back((flat[g.Index(r + 1, c)] - flat[g.Index(r, c)]).norm() * scale);
  const double spacing = Median(lengths);
  *step = spacing > 0 ? std::max(1, int(std::ceil(min_spacing / spacing))) : 1;
  constexpr int kShift = 4;  // sub-pixel vertex positions
  auto to_px = [&](int i) {
    const Eigen::Vector2d p =
        (flat[i] - Eigen::Vector2d(x0, y0)) * scale - Eigen::Vector2d(0.5, 0.5);
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

Json OptionsToJson(const RenderOptions& o) {
  return {{"width", o.width},
          {"height", o.height},
          {"dpi", o.dpi},
          {"page_width_mm", o.page_width_mm},
          {"page_height_mm", o.page_height_mm},
          {"scale", o.scale},
          {"max_pixels", o.max_pixels},
          {"fill", o.fill},
          {"antialias", o.antialias},
          {"deskew", o.deskew},
          {"max_deskew_deg", o.max_deskew_deg},
          {"deskew_by", o.deskew_by},
          {"sample_hidden", o.sample_hidden},
          {"shading", o.shading},
          {"side_snap", o.side_snap},
          {"crop_rule", o.crop_rule},
          {"crop_middle_max_deg", o.crop_middle_max_deg},
          {"extend_cut_sides", o.extend_cut_sides},
          {"texture_cut_sides", o.texture_cut_sides},
          {"scattered_sides", o.scattered_sides},
          {"max_extension", o.cut_sides.max_extension},
          {"page_aspect", o.page_aspect}};
}

Json Vec2(const Eigen::Vector2d& v) { return Json::array({v.x(), v.y()}); }

Json MakeReport(const RenderOptions& options, const RenderInputs& in, const RenderResult& r) {
  Json doc = MakeHeader("docunfold.render", 1, "render", OptionsToJson(options));
  doc["inputs"] = {{"meshes", in.meshes_dir.string()},
                   {"reference", in.reference_file.string()},
                   {"boundary", in.boundary.file.string()},
                   {"grid", {in.meshes.grid.nx, in.meshes.grid.ny}}};
  Json view_masks = Json::array();
  for (const ViewMask& v : in.views) view_masks.push_back(v.file.string());
  doc["inputs"]["view_masks"] = view_masks;
  doc["width"] = r.rectified.cols;
  doc["height"] = r.rectified.rows;
  doc["pixels_per_unit"] = r.pixels_per_unit;
  doc["reference_pixels_per_unit"] = r.reference_pixels_per_unit;
  doc["size_rule"] = r.size_rule;
  doc["capped"] = r.capped;
  doc["rotation_deg"] = r.rotation_deg;
  doc["deskew_source"] = r.deskew_source;
  doc["crop"] = {{"x0", r.crop_x0},
                 {"y0", r.crop_y0},
                 {"x1", r.crop_x1},
                 {"y1", r.crop_y1},
                 {"rule", r.crop_rule}};
  Json sides = Json::object();
  for (int i = 0; i < 4; ++i) {
    const SideFit& s = r.sides[i];
    Json j = {{"real", s.real}, {"used", s.used}, {"samples", s.samples}, {"mapped", s.mapped}};
    if (s.used) {
      j["point"] = Vec2(s.point);
      j["direction"] = Vec2(s.direction);
      j["rms"] = s.rms;
    }
    if (!s.note.empty()) j["note"] = s.note;
    if (s.scattered) j["median_bound"] = s.median_bound;
    if (const CutSideEdge& e = r.reached_sides[i]; e.measured)
      j["reached_past_mesh"] = {
          {"bound", e.bound}, {"extension", e.extension}, {"crossings", e.crossings}};
    if (!s.real && options.extend_cut_sides) {
      const CutSideEdge& e = r.cut_edges[i];
      Json c = {{"measured", e.measured},
                {"edge_seen", e.edge_seen},
                {"crossings", e.crossings},
                {"columns_seen", e.columns_seen},
                {"views", e.views}};
      if (e.measured) {
        c["bound"] = e.bound;
        c["extension"] = e.extension;
      }
      if (!e.note.empty()) c["note"] = e.note;
      j["page_edge_in_other_views"] = c;
    }
    sides[kSideNames[i]] = j;
  }
  doc["sides"] = sides;
  if (const PageFormatFit& f = r.page_format;
      options.page_aspect > 0 && (f.axis >= 0 || !f.note.empty())) {
    // axis -1 with a note: sides of both axes are cut off unseen.
    Json j = {{"aspect", options.page_aspect},
              {"applied", f.applied},
              {"axis", f.axis < 0    ? "both"
                       : f.axis == 0 ? "x"
                                     : "y"}};
    if (f.axis >= 0) {
      j["seen"] = f.seen;
      j["across"] = f.across;
    }
    if (f.applied) j["length"] = f.length;
    if (!f.note.empty()) j["note"] = f.note;
    doc["page_format"] = j;
  }
  doc["fill_rgb"] = {r.fill[2], r.fill[1], r.fill[0]};
  doc["page_fraction"] = r.page_fraction;
  doc["hidden_fraction"] = r.hidden_fraction;
  doc["minified_fraction"] = r.minified_fraction;
  doc["other_view_fraction"] = r.other_view_fraction;
  doc["better_view_fraction"] = r.better_view_fraction;
  doc["shading"] = {{"removed", r.shading_removed}};
  if (r.shading_removed) doc["shading"]["paper_fraction"] = r.shading_paper_fraction;
  Json regs = Json::array();
  for (const ViewRegistration& g : r.registrations)
    regs.push_back({{"view", in.views[g.view].camera.image},
                    {"affine",
                     {{g.affine(0, 0), g.affine(0, 1), g.affine(0, 2)},
                      {g.affine(1, 0), g.affine(1, 1), g.affine(1, 2)}}},
                    {"inliers", g.inliers},
                    {"moved", g.moved},
                    {"agreement", g.agreement},
                    {"used", g.used}});
  doc["other_views"] = regs;
  doc["grid_line_step"] = r.grid_line_step;
  Json timing = Json::object();
  double total = 0;
  for (const auto& [step, seconds] : r.timings) {
    timing[step] = seconds;
    total += seconds;
  }
  timing["total"] = total;
  doc["timing_s"] = timing;
  return doc;
}

// The reader's down `down_image` (reference pixels) carried into M' by the
// affine map pixel -> M' over the text segments' points that lie on M.
std::optional<Eigen::Vector2d> DownInFlat(const RenderInputs& in, const PixelToSurface& lookup,
                                          const Eigen::Vector2d& down_image) {
  std::vector<Eigen::Vector2d> pixels, flat;
  for (const Eigen::Vector2d& p : in.text_points)
    if (const auto sp = lookup.Lookup(p)) {
      pixels.push_back(p);
      flat.push_back(PointOnMesh2d(in.meshes, *sp));
    }
  return CarryDirection(pixels, flat, down_image);
}

// Which way the text lines of M' run in the output (M' turned by `angle`
// radians): along its rows or columns when their lengths agree by 3 to 1.
OrientationOptions OrientationHint(const std::vector<DirectionVote>& text_lines, double angle) {
  OrientationOptions o;
  double across = 0, down = 0;
  for (const DirectionVote& line : text_lines) {
    const double a = line.angle_deg * M_PI / 180 + angle;
    across += line.length * std::abs(std::cos(a));
    down += line.length * std::abs(std::sin(a));
  }
  if (across > 3 * down) o.lines = OrientationOptions::Lines::kAlongRows;
  if (down > 3 * across) o.lines = OrientationOptions::Lines::kAlongColumns;
  return o;
}

}  // namespace

RenderResult Run(const RenderOptions& options, const RenderInputs& in) {
  RenderResult r;
  StepTimer timer(&r.timings);
  CheckSizeOptions(options);
  bool paper_fill = false;
  const cv::Vec3b fixed_fill = ParseFill(options.fill, &paper_fill);
  CheckInputs(in);
  const PinholeCamera& cam = in.camera;
  const fs::path m3 = in.meshes_dir / "mesh3d.ply";

  const ProjectedMesh pm = ProjectMesh(in);
  if (pm.faces_in_view == 0)
    throw InputError(m3.string() + ": no face of M lies inside the reference image " + cam.image +
                     " facing the camera");
  r.reference_pixels_per_unit = pm.density;
  const PixelToSurface lookup(in.meshes, cam);
  timer.Mark("project");

  // Boundary sides onto M', their lines, and the tilt they show.
  Eigen::Vector2d flat_lo = in.meshes.mesh2d[0], flat_hi = flat_lo;
  for (const auto& q : in.meshes.mesh2d) {
    flat_lo = flat_lo.cwiseMin(q);
    flat_hi = flat_hi.cwiseMax(q);
  }
  const double flat_diagonal = (flat_hi - flat_lo).norm();
  std::array<std::vector<Eigen::Vector2d>, 4> side_points;
  const double snap_px = options.side_snap * std::hypot(cam.width, cam.height);
  for (int i = 0; i < 4; ++i) {
    const BoundarySide& side = in.boundary.sides[i];
    int samples = 0;
    if (side.real)
      side_points[i] = MapPolylineOntoFlat(in.meshes, cam, lookup, side.points, snap_px, &samples);
    r.sides[i] = FitSideLine(i, side.real, side_points[i], samples);
    // A side whose samples scatter about their line is not a straight page
    // edge seen on M (the boundary runs over a fold, or M is far off there).
    if (r.sides[i].used && r.sides[i].rms > kMaxSideRms * flat_diagonal) {
      r.sides[i].used = false;
      r.sides[i].scattered = true;
      r.sides[i].note = "samples scatter about their line (rms " +
                        std::to_string(r.sides[i].rms / flat_diagonal) + " of M' diagonal)";
    }
  }
  double angle = 0;
  if (options.deskew) {
    double tilt = TiltOfSides(r.sides);
    std::string source = "sides", what = "boundary lines";
    if (options.deskew_by == "lines") {
      const AxisDirection mode = DominantAxisDirection(in.lines);
      if (mode.lines >= options.deskew_min_lines && mode.share >= 0.5) {
        tilt = mode.angle_deg * M_PI / 180;
        source = "lines";
        what = "the page's lines";
      }
    }
    if (std::abs(tilt) * 180 / M_PI <= options.max_deskew_deg) {
      angle = -tilt;
      r.deskew_source = source;
    } else {
      Log(what + " are " + std::to_string(tilt * 180 / M_PI) +
          " degrees off upright; more than --max-deskew-deg, left as is");
    }
  }
  r.rotation_deg = angle * 180 / M_PI;
  const Eigen::Rotation2Dd rotation(angle);
  std::vector<Eigen::Vector2d> flat = in.meshes.mesh2d;
  for (auto& q : flat) q = rotation * q;
  for (auto& s : r.sides)
    if (s.used) RotateSide(&s, angle);
  Eigen::Vector4d visible = VisibleBox(lookup.raster(), pm.triangles, flat);
  if (!(visible[2] > visible[0] && visible[3] > visible[1]))
    throw InputError(m3.string() + ": the mesh covers no pixel of the reference image");
  if (options.extend_cut_sides) {
    std::array<bool, 4> cut;
    for (int i = 0; i < 4; ++i) cut[i] = !in.boundary.sides[i].real;
    r.cut_edges = FindCutSideEdges(in.meshes, flat, visible, cut, in.views, options.cut_sides);
    for (int i = 0; i < 4; ++i) {
      if (!cut[i]) continue;
      const CutSideEdge& e = r.cut_edges[i];
      if (!e.measured) {
        Log(std::string(kSideNames[i]) + " side cut off by the reference image: " + e.note);
        continue;
      }
      // The box stands in for the sides the crop has no line for.
      visible[BoxIndexOfSide(i)] = e.bound;
      const double axis_extent = i % 2 == 0 ? visible[3] - visible[1] : visible[2] - visible[0];
      const std::string share =
          std::to_string(int(std::lround(100 * e.extension / axis_extent))) + " % of the page";
      Log(std::string(kSideNames[i]) + " side cut off by the reference image: " +
          (e.edge_seen
               ? "the other views see the page edge " + share + " past it (" +
                     std::to_string(e.crossings) + " crossings in " + std::to_string(e.views) +
                     " views)"
               : "the other views see page up to " + share + " past it, but not its edge (" +
                     std::to_string(e.columns_seen) + " columns)"));
    }
  }
  // A real side that M stops short of (its border runs inside the outline
  // where a blank margin has no points, so too few of the side's samples
  // map onto M): the surface is continued past M's border, as for a cut
  // side, until it leaves the page in the reference image itself.
  std::vector<ViewMask> self_view;
  if (options.reach_real_sides) {
    std::array<bool, 4> short_side{};
    for (int i = 0; i < 4; ++i)
      short_side[i] = r.sides[i].real && !r.sides[i].scattered &&
                      (!r.sides[i].used ||
                       r.sides[i].mapped < options.reach_partial_below * r.sides[i].samples);
    if (std::any_of(short_side.begin(), short_side.end(), [](bool s) { return s; })) {
      self_view.push_back({cam,
                           OutlineMask(in.boundary, cam.width, cam.height),
                           in.boundary.file,
                           in.reference_file,
                           {}});
      const std::array<CutSideEdge, 4> reached =
          FindCutSideEdges(in.meshes, flat, visible, short_side, self_view, options.cut_sides);
      for (int i = 0; i < 4; ++i) {
        if (!short_side[i]) continue;
        const CutSideEdge& e = reached[i];
        if (!e.measured || !e.edge_seen || !(e.extension > 0)) continue;
        SideFit& side = r.sides[i];
        if (side.used) {
          // The line where it crosses the middle of the visible box; the
          // reached edge replaces it only if it lies farther out.
          const bool horizontal = i == 0 || i == 2;
          const double mid =
              horizontal ? 0.5 * (visible[0] + visible[2]) : 0.5 * (visible[1] + visible[3]);
          const double line = horizontal ? YAt(side, mid) : XAt(side, mid);
          const bool farther = (i == 0 || i == 3) ? e.bound < line : e.bound > line;
          if (!farther) continue;
          side.used = false;
          side.note = "only " + std::to_string(side.mapped) + " of " +
                      std::to_string(side.samples) +
                      " samples map onto the mesh, and the side lies past their line";
        }
        visible[BoxIndexOfSide(i)] = e.bound;
        r.reached_sides[i] = e;
        const double axis_extent = i % 2 == 0 ? visible[3] - visible[1] : visible[2] - visible[0];
        char share[32];
        std::snprintf(share, sizeof share, "%.1f", 100 * e.extension / axis_extent);
        Log(std::string(kSideNames[i]) + " side lies past M's border: M continued by " + share +
            " % of the page to reach it (" + std::to_string(e.crossings) + " columns)");
      }
    }
  }
  for (int i = 0; i < 4; ++i) {
    if (!r.sides[i].scattered) continue;
    std::vector<double> across;
    for (const auto& p : side_points[i]) {
      const Eigen::Vector2d q = rotation * p;
      across.push_back(i % 2 == 0 ? q.y() : q.x());
    }
    r.sides[i].median_bound = Median(across);
    if (options.scattered_sides == "median") visible[BoxIndexOfSide(i)] = r.sides[i].median_bound;
  }
  CropRect crop =
      ChooseCrop(&r.sides, visible,
                 options.crop_rule == "middle" ? options.crop_middle_max_deg * M_PI / 180 : -1.0);
  for (int i = 0; i < 4; ++i)
    if (r.sides[i].real && !r.sides[i].used && !r.reached_sides[i].measured)
      Log(std::string(kSideNames[i]) + " side not used for the crop: " + r.sides[i].note);
  if (options.page_aspect > 0) {
    std::array<bool, 4> unseen;
    for (int i = 0; i < 4; ++i)
      unseen[i] =
          !in.boundary.sides[i].real && !(r.cut_edges[i].measured && r.cut_edges[i].edge_seen);
    r.page_format = ExtendToPageFormat(&crop, unseen, options.page_aspect);
    const PageFormatFit& f = r.page_format;
    if (f.applied) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "no photo sees where the page ends past its cut %s: the crop lengthened "
                    "from %.3f to %.3f, %.2f times its width (--page-format)",
                    f.axis == 0 ? "left or right" : "top or bottom", f.seen, f.length,
                    f.length / f.across);
      Log(buf);
    } else if (!f.note.empty()) {
      Log("page format not applied: " + f.note);
    }
  }
  r.crop_rule = crop.rule;
  timer.Mark("crop");

  // Output size; the crop is re-centred to a whole number of pixels.
  const SizeChoice size = ChooseSize(options, crop.Width(), crop.Height(), pm.density);
  if (size.capped)
    Log("output reduced to " + std::to_string(size.width) + "x" + std::to_string(size.height) +
        " by --max-pixels");
  const double cx = 0.5 * (crop.x0 + crop.x1), cy = 0.5 * (crop.y0 + crop.y1);
  r.crop_x0 = cx - 0.5 * size.width / size.scale;
  r.crop_x1 = cx + 0.5 * size.width / size.scale;
  r.crop_y0 = cy - 0.5 * size.height / size.scale;
  r.crop_y1 = cy + 0.5 * size.height / size.scale;
  r.pixels_per_unit = size.scale;
  r.size_rule = size.rule;
  r.capped = size.capped;

  // Flat rasterization of M': output pixel centre (x, y) is the point
  // (crop_x0 + (x + 0.5) / s, crop_y0 + (y + 0.5) / s) of M'.
  std::vector<Eigen::Vector3d> screen(flat.size());
  for (size_t i = 0; i < flat.size(); ++i)
    screen[i] = {(flat[i].x() - r.crop_x0) * size.scale - 0.5,
                 (flat[i].y() - r.crop_y0) * size.scale - 0.5, 1.0};
  const RasterResult out_raster = Rasterize(screen, pm.triangles, size.width, size.height);
  timer.Mark("rasterize");

  cv::Mat3b image;
  cv::Mat1b state;
  const SampleStats stats =
      SamplePixels(options, in, pm, flat, out_raster, lookup.raster(), size.scale, &image, &state);
  timer.Mark("sample");

  // The page past the sides the reference image cuts off, from the photos
  // that see it.
  std::vector<const ExtensionStrip*> strips;
  for (const CutSideEdge& e : r.cut_edges)
    if (!e.strip.flat.empty()) strips.push_back(&e.strip);
  const bool better_views = options.better_views.min_gain > 0 && !in.views.empty();
  std::vector<cv::Mat> photos(in.views.size());
  if ((!strips.empty() && options.texture_cut_sides) || better_views)
    for (size_t v = 0; v < in.views.size(); ++v) {
      const ViewMask& view = in.views[v];
      if (view.photo.empty()) continue;
      photos[v] = ReadViewPhoto(view.photo, view.camera, in.cameras_file, cv::IMREAD_COLOR);
    }
  if (better_views) {
    const cv::Mat1b textured = TextureFromBetterViews(
        in.meshes, flat, out_raster, in.camera, size.scale, in.views, photos, options.antialias,
        state == kPage, options.better_views, &image, &r.registrations);
    state.setTo(kOtherView, textured);
    r.better_view_fraction = cv::countNonZero(textured) / (double(size.width) * size.height);
    timer.Mark("better_views");
  }
  // The margin reached past M's border, from the reference photo itself.
  std::vector<const ExtensionStrip*> reached_strips;
  for (const CutSideEdge& e : r.reached_sides)
    if (!e.strip.flat.empty()) reached_strips.push_back(&e.strip);
  if (!reached_strips.empty()) {
    const cv::Mat1b textured = TextureStrips(
        reached_strips, self_view, {in.reference}, r.crop_x0, r.crop_y0, size.scale,
        options.antialias, image.clone(), state == kPage, state == kOutside, &image, nullptr,
        /*own_photo=*/true);
    state.setTo(kPage, textured);
    timer.Mark("reached_sides");
  }
  if (!strips.empty() && options.texture_cut_sides) {
    const cv::Mat3b reference_render = image.clone();
    const cv::Mat1b textured = TextureStrips(
        strips, in.views, photos, r.crop_x0, r.crop_y0, size.scale, options.antialias,
        reference_render, state == kPage, state == kOutside, &image, &r.registrations);
    state.setTo(kOtherView, textured);
    r.other_view_fraction = cv::countNonZero(textured) / (double(size.width) * size.height);
    timer.Mark("other_views");
  }

  r.fill = paper_fill ? MedianColour(image, state) : fixed_fill;
  const cv::Mat1b unfilled = (state != kPage) & (state != kHiddenSampled) & (state != kOtherView);
  image.setTo(cv::Scalar(r.fill[0], r.fill[1], r.fill[2]), unfilled);
  if (options.shading == "remove") {
    ShadingRemoval removal = RemoveShading(image, options.shading_removal);
    image = removal.image;
    r.shading_removed = true;
    r.shading_paper_fraction = removal.paper_fraction;
    timer.Mark("shading");
  }
  const double n = double(size.width) * size.height;
  r.page_fraction = stats.page / n;
  r.hidden_fraction = stats.hidden / n;
  r.minified_fraction = stats.minified / n;
  r.rectified = image;
  r.page_mask = ~unfilled;
  r.rectified_grid = DrawGrid(image, state, in.meshes, flat, r.crop_x0, r.crop_y0, size.scale,
                              options.grid_color, options.grid_min_spacing_px, &r.grid_line_step);
  timer.Mark("fill_and_grid");
  Json orientation = {{"checked", options.orient}};
  if (options.orient) {
    const OrientationOptions hint = OrientationHint(in.text_lines, angle);
    Orientation o = FindOrientation(r.rectified, hint);
    // The reader's down in M': lines.json's, else features.json's carried
    // into M' here; (0, 0) when neither is known.
    Eigen::Vector2d down = in.text_down.value_or(Eigen::Vector2d::Zero());
    std::string down_from = "lines.json";
    if (!in.text_down && in.text_down_image) {
      down = DownInFlat(in, lookup, *in.text_down_image).value_or(Eigen::Vector2d::Zero());
      down_from = "features.json";
    }
    if (!o.decided && down.norm() > 0) {
      // Print too small to read: the side the baselines lie on (found by
      // detect-features, carried into M' by optimize or here) says which way
      // is down. Output y is M' turned by `angle`; turn so that down is +y.
      const Eigen::Vector2d d = Eigen::Rotation2Dd(angle) * down;
      // Clockwise quarter turns map the image's down (0, 1) to: 0 -> (0, 1),
      // 1 -> (-1, 0), 2 -> (0, -1), 3 -> (1, 0); pick the one taking d there.
      const int turns =
          std::abs(d.y()) >= std::abs(d.x()) ? (d.y() > 0 ? 0 : 2) : (d.x() > 0 ? 1 : 3);
      o.quarter_turns = turns;
      o.note += "; turned by the side the text's baselines lie on (" + down_from + ")";
      orientation["by"] = "baselines";
    } else if (!o.decided && hint.lines == OrientationOptions::Lines::kAlongColumns) {
      // Nothing says which way up, but the text lines run down the page: a
      // quarter turn at least makes them run across it (the one with more
      // words read, else clockwise).
      o.quarter_turns = o.words[3] > o.words[1] ? 3 : 1;
      o.note += "; its text lines (lines.json) ran down the page: turned " +
                std::to_string(90 * o.quarter_turns) + " degrees so that they run across";
      orientation["by"] = "text lines";
    }
    orientation["readable_words"] = o.words;
    orientation["decided"] = o.decided;
    if (!o.note.empty()) {
      orientation["note"] = o.note;
      Log(o.note);
    }
    r.quarter_turns = o.quarter_turns;
    if (o.quarter_turns != 0) {
      r.rectified = Turn(r.rectified, o.quarter_turns);
      r.rectified_grid = Turn(r.rectified_grid, o.quarter_turns);
      r.page_mask = Turn(r.page_mask, o.quarter_turns);
      Log("turned the page " + std::to_string(90 * o.quarter_turns) +
          " degrees clockwise so that its text reads upright");
    }
    timer.Mark("orientation");
  }
  orientation["quarter_turns_clockwise"] = r.quarter_turns;
  r.report = MakeReport(options, in, r);
  r.report["orientation"] = orientation;
  return r;
}

}  // namespace docunfold::render
