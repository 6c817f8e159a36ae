// Run: render's steps in order (render_internal.h), the checks of its
// options and inputs, and the steps after sampling (texture past M's border,
// fill and grid, the upright turn).
#include "stages/render/render.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "common/errors.h"
#include "common/program.h"
#include "common/raster.h"
#include "stages/render/orientation.h"
#include "stages/render/render_internal.h"

namespace docunfold::render {
namespace {

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

// The output frame: the crop in a whole number of pixels (r->crop_*,
// r->pixels_per_unit(_y), r->size_rule) and M' rasterized in it.
struct OutputFrame {
  SizeChoice size;
  PixelFrame pixels;
  std::vector<Eigen::Vector2d> pixel;  // M''s vertices in output pixels
  RasterResult raster;
};

OutputFrame FrameOutput(const RenderOptions& options, const CropRect& crop,
                        const std::vector<Eigen::Vector2d>& flat, const ProjectedMesh& pm,
                        RenderResult* r) {
  OutputFrame frame;
  const SizeChoice size = ChooseSize(options, crop.Width(), crop.Height(), pm.density);
  if (size.capped)
    Log("output reduced to " + std::to_string(size.width) + "x" + std::to_string(size.height) +
        " by --max-pixels");
  // The size rounds the crop to whole pixels; the crop is kept and each axis
  // gets its own scale, so that the page's sides stay the image's edges (a
  // re-centred crop moves them by up to a quarter pixel; pixels square to
  // 0.1 % matter less). docs/decisions/render.md, "The crop kept whole: a
  // scale per axis".
  r->crop_x0 = crop.x0;
  r->crop_x1 = crop.x1;
  r->crop_y0 = crop.y0;
  r->crop_y1 = crop.y1;
  frame.pixels.origin = Eigen::Vector2d(crop.x0, crop.y0);
  frame.pixels.scale = Eigen::Vector2d(size.width / crop.Width(), size.height / crop.Height());
  r->pixels_per_unit = frame.pixels.scale.x();
  r->pixels_per_unit_y = frame.pixels.scale.y();
  r->size_rule = size.rule;
  r->capped = size.capped;

  std::vector<Eigen::Vector3d> screen(flat.size());
  for (size_t i = 0; i < flat.size(); ++i) {
    frame.pixel.push_back(frame.pixels.ToPixel(flat[i]));
    screen[i] = {frame.pixel[i].x(), frame.pixel[i].y(), 1.0};
  }
  frame.raster = Rasterize(screen, pm.triangles, size.width, size.height);
  frame.size = size;
  return frame;
}

// The page past M's border: the margin reached past it from the reference
// photo itself (`self_view`), the page past the sides the reference image
// cuts off from the photos that see it (r->registrations,
// r->other_view_fraction).
void TexturePastMesh(const RenderOptions& options, const RenderInputs& in,
                     const std::vector<ViewMask>& self_view, const OutputFrame& frame,
                     const TexturePhotos& photos, cv::Mat3b* image_io, cv::Mat1b* state_io,
                     RenderResult* r, StepTimer* timer) {
  cv::Mat3b& image = *image_io;
  cv::Mat1b& state = *state_io;
  std::vector<const ExtensionStrip*> strips;
  for (const CutSideEdge& e : r->cut_edges)
    if (!e.strip.flat.empty()) strips.push_back(&e.strip);
  // The margin reached past M's border, from the reference photo itself.
  std::vector<const ExtensionStrip*> reached_strips;
  for (const CutSideEdge& e : r->reached_sides)
    if (!e.strip.flat.empty()) reached_strips.push_back(&e.strip);
  if (!reached_strips.empty()) {
    const cv::Mat1b textured = TextureStrips(reached_strips, self_view, {photos.reference},
                                             frame.pixels, options.antialias, image.clone(),
                                             state == kPage, state == kOutside, &image, nullptr,
                                             /*own_photo=*/true);
    state.setTo(kPage, textured);
    timer->Mark("reached_sides");
  }
  if (!strips.empty() && options.texture_cut_sides) {
    const cv::Mat3b reference_render = image.clone();
    const cv::Mat1b textured = TextureStrips(strips, in.views, photos.views, frame.pixels,
                                             options.antialias, reference_render, state == kPage,
                                             state == kOutside, &image, &r->registrations);
    state.setTo(kOtherView, textured);
    r->other_view_fraction = cv::countNonZero(textured) / double(image.total());
    timer->Mark("other_views");
  }
}

// The fill where no photo shows the page, the light's shading divided out
// (kRemove), the fractions of the output and the grid overlay: r->rectified,
// r->page_mask, r->rectified_grid.
void FillAndDrawGrid(const RenderOptions& options, const RenderInputs& in,
                     const std::vector<Eigen::Vector2d>& flat, const OutputFrame& frame,
                     const SampleStats& stats, bool paper_fill, const cv::Vec3b& fixed_fill,
                     cv::Mat3b image, const cv::Mat1b& state, RenderResult* r, StepTimer* timer) {
  r->fill = paper_fill ? MedianColour(image, state) : fixed_fill;
  const cv::Mat1b unfilled = (state != kPage) & (state != kHiddenSampled) & (state != kOtherView);
  image.setTo(cv::Scalar(r->fill[0], r->fill[1], r->fill[2]), unfilled);
  if (options.shading == Shading::kRemove) {
    ShadingRemoval removal = RemoveShading(image, options.shading_removal);
    image = removal.image;
    r->shading_removed = true;
    r->shading_paper_fraction = removal.paper_fraction;
    timer->Mark("shading");
  }
  const double n = double(image.total());
  r->page_fraction = stats.page / n;
  r->hidden_fraction = stats.hidden / n;
  r->minified_fraction = stats.minified / n;
  r->rectified = image;
  r->page_mask = ~unfilled;
  r->rectified_grid = DrawGrid(image, state, in.meshes, flat, frame.pixels, options.grid_color,
                               options.grid_min_spacing_px, &r->grid_line_step);
}

// Turns the images by quarter turns so that the page's text reads upright
// (options.orient; r->quarter_turns); returns render.json's "orientation".
Json Orient(const RenderOptions& options, const RenderInputs& in, const PixelToSurface& lookup,
            double angle, RenderResult* r, StepTimer* timer) {
  Json orientation = {{"checked", options.orient}};
  if (options.orient) {
    const OrientationOptions hint = OrientationHint(in.text_lines, angle);
    Orientation o = FindOrientation(r->rectified, hint);
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
    r->quarter_turns = o.quarter_turns;
    if (o.quarter_turns != 0) {
      r->rectified = Turn(r->rectified, o.quarter_turns);
      r->rectified_grid = Turn(r->rectified_grid, o.quarter_turns);
      r->page_mask = Turn(r->page_mask, o.quarter_turns);
      if (!r->texture_labels.empty()) r->texture_labels = Turn(r->texture_labels, o.quarter_turns);
      Log("turned the page " + std::to_string(90 * o.quarter_turns) +
          " degrees clockwise so that its text reads upright");
    }
    timer->Mark("orientation");
  }
  orientation["quarter_turns_clockwise"] = r->quarter_turns;
  return orientation;
}

// The print straightened in the finished (turned) images, the page mask and
// the texture labels moved with it.
void Straighten(const RenderOptions& options, RenderResult* r, StepTimer* timer) {
  if (!options.straighten.enabled) return;
  const Straightening s = FindStraightening(r->rectified, options.straighten);
  if (s.rows.max_shift_px > 0 || s.columns.max_shift_px > 0) {  // else the maps are the identity
    r->rectified = ApplyStraightening(r->rectified, s, cv::INTER_CUBIC);
    r->rectified_grid = ApplyStraightening(r->rectified_grid, s, cv::INTER_CUBIC);
    r->page_mask = ApplyStraightening(r->page_mask, s, cv::INTER_NEAREST);
    r->texture_labels = ApplyStraightening(r->texture_labels, s, cv::INTER_NEAREST);
  }
  r->straightened_rows = s.rows;
  r->straightened_columns = s.columns;
  timer->Mark("straighten");
}
}  // namespace

RenderResult Run(const RenderOptions& options, const RenderInputs& in) {
  RenderResult r;
  StepTimer timer;
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

  const std::array<std::vector<Eigen::Vector2d>, 4> side_points = FitSides(options, in, lookup, &r);
  const double angle = DeskewAngle(options, in, &r);
  r.rotation_deg = angle * 180 / M_PI;
  const CropStep crop = CropPage(options, in, pm, angle, side_points, &r);
  timer.Mark("crop");

  const OutputFrame frame = FrameOutput(options, crop.crop, crop.flat, pm, &r);
  timer.Mark("rasterize");

  const bool fusion = options.texture == Texture::kFusion;
  const bool past_mesh = options.texture_cut_sides &&
                         std::any_of(r.cut_edges.begin(), r.cut_edges.end(),
                                     [](const CutSideEdge& e) { return !e.strip.flat.empty(); });
  const TexturePhotos photos = ReadTexturePhotos(options, in, fusion || past_mesh);
  timer.Mark("read_photos");
  cv::Mat3b image;
  cv::Mat1b state;
  const SampleStats stats =
      fusion ? FusePixels(options, in, pm, crop.flat, frame.pixel, frame.raster, pm.raster,
                          frame.size.scale, photos, &image, &state, &r)
             : SamplePixels(options, in, photos.reference, pm, crop.flat, frame.raster, pm.raster,
                            frame.size.scale, &image, &state);
  timer.Mark("sample");

  TexturePastMesh(options, in, crop.self_view, frame, photos, &image, &state, &r, &timer);
  FillAndDrawGrid(options, in, crop.flat, frame, stats, paper_fill, fixed_fill, image, state, &r,
                  &timer);
  timer.Mark("fill_and_grid");
  r.orientation = Orient(options, in, lookup, angle, &r, &timer);
  Straighten(options, &r, &timer);
  r.timings = timer.steps();
  return r;
}
}  // namespace docunfold::render
