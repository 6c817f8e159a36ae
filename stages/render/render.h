// render: the flat page out of the pipeline (the paper's "Image generation
// of rectified document"). M' is texture-mapped with the
// reference image through M: every output pixel is a point of M' (triangle
// and barycentrics), the same point of M is projected by the reference
// camera and the reference image is sampled there (bicubic, filtered over
// the pixel's footprint when minifying). The output is cropped to the
// rectangle bounded by the lines fitted to the real boundary sides in M'.
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/axis_direction.h"
#include "common/camera.h"
#include "common/grid_mesh.h"
#include "common/json_io.h"
#include "common/option_table_fwd.h"
#include "common/page_files.h"
#include "common/shading.h"
#include "common/texture_fusion.h"
#include "stages/render/cut_sides.h"
#include "stages/render/page_edge.h"
#include "stages/render/print_straightening.h"
#include "stages/render/view_sides.h"

namespace docunfold::render {

namespace fs = std::filesystem;

// Long-to-short side ratios of paper formats (render --page-format).
inline constexpr double kIsoAspect = 1.4142135623730951;  // ISO 216: A4, A5, ...
inline constexpr double kLetterAspect = 11.0 / 8.5;       // US Letter
inline constexpr double kLegalAspect = 14.0 / 8.5;        // US Legal

// Which lines the deskew turn follows (RenderOptions::deskew_by).
enum class DeskewBy { kLines, kSides };

// Which photos colour the page (RenderOptions::texture).
enum class Texture { kFusion, kReference };

// What becomes of the light's shading (RenderOptions::shading).
enum class Shading { kKeep, kRemove };

// How the output size is chosen. At most one of width, height, dpi and
// scale may be set (their flags exclude each other; Run throws UsageError
// otherwise).
struct RenderOptions {
  // Output width or height in pixels (0 = not set); the other side follows
  // the crop's aspect ratio, pixels are square.
  int width = 0;
  int height = 0;
  // Dots per inch on the physical page. Photos carry no absolute scale, so
  // dpi needs the physical size of the crop: page_width_mm (the crop's width,
  // i.e. the page's width whenever its left and right sides are real) or
  // page_height_mm. 0 = not set.
  double dpi = 0;
  double page_width_mm = 0;
  double page_height_mm = 0;
  // Multiplier of the reference image's pixel density on the page (the
  // default size: the median over visible faces of sqrt(area in the
  // reference image / area in M') pixels per unit of M'). 0 = not set (1).
  double scale = 0;
  // Upper bound on width*height (25 MP: an A4 page at ~500 dpi; render needs
  // about 40 bytes per output pixel). The default size is scaled down to fit
  // (and logged); an explicitly requested size above it is a usage error.
  double max_pixels = 25e6;
  // Fill for crop pixels that show no page: outside M', or points of the page
  // the reference view does not see (hidden by the page itself, seen from
  // behind or outside the image). "paper" = the per-channel median colour of
  // the rendered page, "white", or "#RRGGBB".
  std::string fill = "paper";
  // Pre-filter when minifying (image pyramid + anisotropic taps). Off only to
  // measure what it buys.
  bool antialias = true;
  // Turn M' by the small angle that makes the page's lines axis aligned (at
  // most max_deskew_deg; larger tilts are left alone and logged). kLines:
  // the direction most of the length of optimize's lines (lines.json beside
  // the meshes: text rows, rules and the real sides) follows, when at least
  // deskew_min_lines agree on it; else, and with kSides, the lines fitted
  // to the real boundary sides mapped onto M'.
  bool deskew = true;
  double max_deskew_deg = 20;
  DeskewBy deskew_by = DeskewBy::kLines;
  int deskew_min_lines = 8;
  // Sample the reference image even where the page is hidden from the
  // reference view by the page itself or seen from behind (by default such
  // pixels get the fill colour). Points outside the image are always filled.
  bool sample_hidden = false;
  // Boundary sides mapped onto M: a sample whose viewing ray misses M is
  // taken on the plane of the nearest face of M within this distance (the
  // mesh border may run a little inside the segmented outline: init-mesh
  // keeps a margin); farther samples are dropped. Fraction of the reference
  // image's diagonal (0.006: 12 px at 1600x1200, 30 px at 4000x3000).
  double side_snap = 0.006;
  // Turn the result by quarter turns so that its text reads upright
  // (Tesseract reads it each way; see orientation.h). The boundary cannot
  // tell a page's top from its sides, so without this the page may come out
  // on its side or upside down.
  bool orient = true;
  // Where a side of the page is cut off by the reference image's border,
  // look for the page edge past it in the other views' page masks
  // (cut_sides.h) and extend the crop to it; the part no photo textures
  // gets the fill colour. Off: the crop stops where the reference view does.
  bool extend_cut_sides = true;
  // Where the page is cut off and no photo sees its edge, lengthen the crop
  // across the cut to the page of this long-to-short side ratio
  // (ExtendToPageFormat in crop.h), the part no photo shows in the fill
  // colour: the whole page at its proportions, not the part seen. 0 (the
  // default): the crop stops where the photos do. Not the default: it helps
  // only a page of the format given, and a flat fill gives the evaluation's
  // flow nothing to follow (see docs/decisions/render.md, "A cut-off page
  // completed to its format").
  double page_aspect = 0;
  // Texture the page found past cut sides from the other photos that see
  // it (RenderInputs::views[].photo); off: the fill colour.
  bool texture_cut_sides = true;
  // Where M stops short of a real side (too few of its samples map onto
  // M), continue M past its border to the outline in the reference image
  // and crop there; off: the crop stops where M does.
  bool reach_real_sides = true;
  // A real side of which fewer than this fraction of the samples map onto M
  // is reached as well, though its line is fitted: those samples are only
  // where M gets to the side, and the crop follows the farther of the line
  // and the reached edge (0: only sides too short to fit).
  double reach_partial_below = 0.6;
  // Warp M' so that the used sides' lines within this many degrees of their
  // axes become the crop's edges (SideWarp in crop.h): a side a little off
  // its axis in M' is M' a little wrong there, and the page near it with it.
  // 0: the crop is inscribed in the lines, at each line's tighter end.
  double warp_max_slant_deg = 3;
  CutSideOptions cut_sides;
  // A side the reference photo sees edge-on, placed from the photo that
  // sees it best (view_sides.h).
  EdgeOnSideOptions edge_on_sides;
  // kRemove: divide out the light's shading (folds, curls, shadows) so the
  // paper comes out one even colour, as a scan (common/shading.h); kKeep:
  // the reference photo's brightness, as the paper's method renders it (and
  // as the benchmark's oracle does).
  Shading shading = Shading::kKeep;
  ShadingOptions shading_removal;
  // The printed rows and columns straightened in the finished image
  // (print_straightening.h): the waviness M' left behind.
  StraightenOptions straighten;
  // Every photo's page colour continued past its outline before it is
  // sampled (page_edge.h): no rim of table colour along the crop's edges.
  PageEdgeOptions page_edge;
  // kFusion: every photo that sees a part of the page better than the
  // reference does colours it there (common/texture_fusion.h: levelled,
  // registered, seams where the photos agree); kReference: the reference
  // photo alone, as the paper's method renders it.
  Texture texture = Texture::kFusion;
  FusionOptions fusion;
  // Grid overlay colour (BGR) and minimum spacing of drawn grid lines in
  // output pixels (denser grids are drawn every k-th line).
  cv::Scalar grid_color = cv::Scalar(40, 40, 230);
  double grid_min_spacing_px = 12;
};

struct RenderInputs {
  PinholeCamera camera;  // reference camera (world frame = its frame)
  cv::Mat reference;     // reference.png, 8-bit BGR
  Boundary boundary;
  MeshPair meshes;
  // Directions and lengths in M' of the lines in lines.json beside the
  // meshes (optimize's); empty when there is none (init-mesh's meshes).
  std::vector<DirectionVote> lines;
  // Of those, the text lines, each by its direction along the line (not
  // its normal): which way the page's text runs in M'.
  std::vector<DirectionVote> text_lines;
  // The reader's down in M' (lines.json text_down_flat), when known: which
  // way up the page is when Tesseract cannot read its print.
  std::optional<Eigen::Vector2d> text_down;
  // Without lines.json (init-mesh's meshes): the reader's down in the
  // reference image (features.json text_down) and the points of the text
  // segments, which carry it into M'.
  std::optional<Eigen::Vector2d> text_down_image;
  std::vector<Eigen::Vector2d> text_points;
  // Page masks of the other views (20_boundary/views/<name>/mask.png, when
  // segment-boundary was given --views), with their cameras and photos.
  std::vector<ViewMask> views;
  // The other registered photos in sfm's order as the reference, best first
  // (cameras.json reference_selection; empty when it has none): what to
  // suggest when M looks wrong.
  std::vector<std::string> other_references;
  // Where each input came from, for error messages and the report.
  fs::path cameras_file, reference_file, meshes_dir;
};

// The crop lengthened past cut sides no photo sees the edge of (crop.h).
struct PageFormatFit {
  bool applied = false;
  int axis = -1;      // 0: x (the left and right sides), 1: y (top and bottom)
  double seen = 0;    // the crop's extent along that axis before, units of M'
  double across = 0;  // its extent across it
  double length = 0;  // the format's length along the axis (applied)
  std::string note;   // why not applied, when some side's edge is unseen
};

// Per boundary side: what its mapping onto M' gave.
struct SideFit {
  bool real = false;
  bool used = false;                                // real, and enough of it maps onto M
  int samples = 0;                                  // pixels sampled along the side
  int mapped = 0;                                   // of those, mapped onto M and kept as inliers
  Eigen::Vector2d point = Eigen::Vector2d::Zero();  // on the line (M')
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();  // unit
  double rms = 0;                                        // residual of the fit, M' units
  std::string note;                                      // why a real side was not used
  // A real side whose samples scatter about their line: the median of their
  // coordinate across it (y for top and bottom, x for left and right, M'
  // after the deskew turn), which then bounds the crop.
  bool scattered = false;
  double median_bound = 0;
  // Median |cos| between the reference's rays along a used side and M's
  // normal where they meet it, and the other photo that placed the side
  // because the reference sees it edge-on (view_sides.h; empty: the
  // reference), with its own median |cos| there.
  std::optional<double> reference_cos;  // nullopt: no ray along it meets M
  std::string placed_by;
  double placed_by_cos = 0;
};

struct RenderResult {
  cv::Mat rectified;       // 8-bit BGR
  cv::Mat rectified_grid;  // the same with the edges of M' drawn
  cv::Mat1b page_mask;     // 255 where `rectified` shows the page (not fill)
  // Crop rectangle in M' units (after the deskew rotation) and the scale.
  double crop_x0 = 0, crop_y0 = 0, crop_x1 = 0, crop_y1 = 0;
  double pixels_per_unit = 0;            // output pixels per unit of M' along x
  double pixels_per_unit_y = 0;          // and along y (within half a pixel of it over the crop)
  double reference_pixels_per_unit = 0;  // the reference image's density
  double rotation_deg = 0;               // deskew applied to M'
  std::string deskew_source = "none";    // what it was taken from: lines, sides, none
  std::string crop_rule;                 // "boundary-lines", "real-sides-and-visible-mesh",
                                         // "visible-mesh"
  std::string size_rule;                 // "reference-density", "width", "height", "dpi", "scale"
  bool capped = false;                   // the default size was reduced to max_pixels
  std::array<SideFit, 4> sides;
  // What the user should know about the result (render.json "warnings").
  std::vector<std::string> warnings;
  // The sides whose lines the crop's edges were warped onto (SideWarp), and
  // the largest move of a crop corner (M' units).
  std::array<bool, 4> warped_sides{};
  double warp_max_shift = 0;
  Eigen::Vector4d warp_box = Eigen::Vector4d::Zero();  // x0 y0 x1 y1 the lines went to
  std::array<CutSideEdge, 4> cut_edges;                // the page edge past cut sides
  std::array<CutSideEdge, 4> reached_sides;            // real sides past M's border
  PageFormatFit page_format;                           // the crop lengthened past unseen cut sides
  std::vector<ViewRegistration> registrations;         // of the views textured from
  cv::Vec3b fill;
  double page_fraction = 0;        // output pixels showing the page
  double hidden_fraction = 0;      // output pixels on M' but not seen
  double minified_fraction = 0;    // output pixels that needed pre-filtering
  double other_view_fraction = 0;  // output pixels from another view's photo
  bool shading_removed = false;
  double shading_paper_fraction = 0;  // of the image taken as paper (shading = remove)
  StraightenPass straightened_rows, straightened_columns;  // options.straighten
  int grid_line_step = 1;
  // Clockwise quarter turns applied to the images after rendering (the crop
  // and pixels_per_unit above refer to the unturned image).
  int quarter_turns = 0;
  // kFusion: which photo coloured each pixel of M' (texture_fusion.h's
  // labels, indices into texture_views: the reference, then the views with a
  // photo), turned as `rectified`; and what each photo contributed.
  cv::Mat1b texture_labels;
  std::vector<FusionViewReport> texture_views;
  double texture_unseen = 0;  // fraction of M' in the crop no photo sees
  std::vector<std::pair<std::string, double>> texture_timings;  // the fusion's steps
  std::vector<std::pair<std::string, double>> timings;          // seconds per step
  Json orientation;  // how the page was turned upright (render.json's "orientation")
};

// Declares every option of render (all but the paths) in `table`, bound to
// the fields of `o`; their values when called are the defaults.
void DeclareOptions(OptionTable& table, RenderOptions* o);

// --page-format's text: iso, letter, legal, none (0) or a long-to-short side
// ratio between 1 and 10, into *aspect. Returns "" when it took the text,
// else what is wrong with it.
std::string ParsePageFormat(const std::string& text, double* aspect);
// The text ParsePageFormat reads as `aspect`: a format's name or the ratio.
std::string PageFormatText(double aspect);

// Reads and validates everything render needs; InputError naming the file
// and the problem otherwise.
// `images_dir` (optional): the photos, for the page past cut sides.
// `features_file` (optional): features.json, for which way up the page is
// when Tesseract cannot tell and there is no lines.json beside the meshes.
RenderInputs ReadRenderInputs(const fs::path& sfm_dir, const fs::path& boundary_dir,
                              const fs::path& meshes_dir, const fs::path& images_dir = {},
                              const fs::path& features_file = {});

// Renders the rectified page. Throws InputError for inconsistent inputs
// (image sizes, mesh behind the camera or out of view) and UsageError for
// contradictory size options.
RenderResult Run(const RenderOptions& options, const RenderInputs& inputs);

// render.json (docunfold.render) for `result`, with `options_record` (the
// option table's record) as its producer's options.
Json RenderReport(const RenderOptions& options, const RenderInputs& inputs,
                  const RenderResult& result, const Json& options_record);

// Writes rectified.png, rectified_grid.png, texture_labels.png (kFusion:
// DrawLabels of the labels) and `report` as render.json into `out_dir`: all
// or none (OutputError).
void WriteRenderOutputs(const fs::path& out_dir, const RenderResult& result, const Json& report);

}  // namespace docunfold::render
