// render: texture-maps M' with the reference image through M and writes the
// cropped, rectified page. See render.h and the README section "render".
#include <chrono>
#include <optional>
#include <string>

#include "common/cli.h"
#include "stages/render/render.h"

namespace {

// --page-format as a long-to-short side ratio (0: none); nullopt when it is
// neither a format's name nor a ratio between 1 and 10.
std::optional<double> PageAspect(const std::string& v) {
  if (v == "iso") return docunfold::render::kIsoAspect;
  if (v == "letter") return docunfold::render::kLetterAspect;
  if (v == "legal") return docunfold::render::kLegalAspect;
  if (v == "none") return 0.0;
  try {
    size_t used = 0;
    const double ratio = std::stod(v, &used);
    if (used == v.size() && ratio >= 1 && ratio <= 10) return ratio;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace docunfold;
  LimitOpenMpThreads(argv);
  render::RenderOptions o;
  std::string sfm, boundary, meshes, out;
  CLI::App app{
      "render: the flat, cropped page from the meshes M (mesh3d.ply) and M' "
      "(mesh2d.ply) and the reference image"};
  app.add_option("--sfm", sfm, "sfm output folder (cameras.json, reference.png)")->required();
  app.add_option("--boundary", boundary, "segment-boundary output folder (boundary.json)")
      ->required();
  app.add_option("--meshes", meshes,
                 "folder with mesh3d.ply and mesh2d.ply (50_optimize or 40_init)")
      ->required();
  app.add_option("--out", out, "output folder: rectified.png, rectified_grid.png, render.json")
      ->required();
  auto* width = app.add_option("--width", o.width,
                               "output width in pixels (default: keep the "
                               "reference image's pixel density on the page)");
  auto* height = app.add_option("--height", o.height, "output height in pixels");
  auto* dpi = app.add_option("--dpi", o.dpi,
                             "dots per inch; needs --page-width-mm or "
                             "--page-height-mm");
  auto* scale = app.add_option("--scale", o.scale,
                               "multiple of the reference image's pixel "
                               "density on the page");
  width->excludes(height, dpi, scale);
  height->excludes(dpi, scale);
  dpi->excludes(scale);
  auto* pw = app.add_option("--page-width-mm", o.page_width_mm,
                            "physical width of the crop (the page's width when its left and "
                            "right sides are real), for --dpi");
  auto* ph = app.add_option("--page-height-mm", o.page_height_mm,
                            "physical height of the crop, for --dpi");
  pw->excludes(ph);
  app.add_option("--max-pixels", o.max_pixels, "cap on width*height")->capture_default_str();
  app.add_option("--fill", o.fill,
                 "colour where the crop shows no visible page: paper (median "
                 "page colour), white or #RRGGBB")
      ->capture_default_str();
  bool no_antialias = false, no_deskew = false, no_orient = false;
  app.add_flag("--no-orient", no_orient,
               "keep the page as M' has it, even if its text reads sideways or "
               "upside down (by default Tesseract decides which way up)");
  app.add_flag("--no-antialias", no_antialias, "plain bicubic even when minifying");
  app.add_flag("--no-deskew", no_deskew, "do not turn M' to make the boundary lines axis aligned");
  app.add_option("--deskew-by", o.deskew_by,
                 "lines: the direction most of optimize's lines (lines.json beside the "
                 "meshes) follow, else the sides; sides: the real boundary sides")
      ->capture_default_str()
      ->check(CLI::IsMember({"lines", "sides"}));
  app.add_option("--crop", o.crop_rule,
                 "inscribed: the rectangle inside the lines of the real sides; middle: "
                 "through those within --crop-middle-max-deg of their axis where they cross "
                 "the middle of the page (the others inscribed)")
      ->capture_default_str()
      ->check(CLI::IsMember({"inscribed", "middle"}));
  app.add_option("--crop-middle-max-deg", o.crop_middle_max_deg,
                 "--crop middle: sides slanted more than this in M' are inscribed")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 45.0));
  app.add_option("--max-deskew-deg", o.max_deskew_deg, "largest tilt corrected")
      ->capture_default_str();
  app.add_option("--side-snap", o.side_snap,
                 "boundary samples up to this far outside M (fraction of the "
                 "image diagonal) "
                 "are mapped onto the plane of the nearest face")
      ->capture_default_str();
  app.add_flag("--sample-hidden", o.sample_hidden,
               "sample the reference image also where it does not see the page");
  app.add_option("--scattered-sides", o.scattered_sides,
                 "a real side whose samples scatter about their line in M' bounds the crop "
                 "by their median (median) or not at all (box: the part of M' the reference "
                 "view sees)")
      ->capture_default_str()
      ->check(CLI::IsMember({"median", "box"}));
  app.add_option("--shading", o.shading,
                 "remove: divide out the light's shading (folds, curls, shadows) so that the "
                 "paper comes out one even colour, as from a scanner (far better OCR); keep: "
                 "the reference photo's brightness, as the paper's method renders it")
      ->capture_default_str()
      ->check(CLI::IsMember({"keep", "remove"}));
  bool no_extend = false, no_texture_cut = false, no_reach = false;
  std::string images, features;
  app.add_option("--features", features,
                 "features.json (30_features/): when Tesseract cannot tell which way up the "
                 "page is and the meshes have no lines.json beside them (init-mesh's), the "
                 "side the text's baselines lie on decides");
  app.add_option("--images", images,
                 "the photos (<data>/images): the page found past a cut side is textured "
                 "from the other views that see it (without: the fill colour)");
  app.add_flag("--no-texture-cut-sides", no_texture_cut,
               "fill the page found past a cut side instead of texturing it");
  app.add_flag("--no-reach-real-sides", no_reach,
               "where M stops short of a real side (a blank margin with no points), crop "
               "where M stops instead of continuing M to the side's outline");
  app.add_option("--reach-partial-below", o.reach_partial_below,
                 "also reach a real side of which fewer than this fraction of the samples map "
                 "onto M (they are only where M gets to it), and crop at the farther of its "
                 "line and the reached edge (0 = only sides too short to fit)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("--no-extend-cut-sides", no_extend,
               "stop the crop where the reference image cuts the page off (by default the "
               "page edge past it is looked for in the other views' page masks, "
               "<boundary>/views/*/mask.png)");
  app.add_option("--max-extension", o.cut_sides.max_extension,
                 "how far past a cut side the page edge is looked for, as a fraction of "
                 "what the reference view shows along that axis")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  std::string page_format = "none";
  app.add_option("--page-format", page_format,
                 "where the page is cut off and no photo sees its edge, lengthen the crop "
                 "across the cut to the whole page of this format, the unseen part in the "
                 "fill colour: iso (A4, A5, ...: sides 1:1.414), letter (1:1.294), legal "
                 "(1:1.647), a long-to-short ratio such as 1.5, or none (stop where the "
                 "photos do)")
      ->capture_default_str()
      ->check([](const std::string& v) -> std::string {
        return PageAspect(v) ? ""
                             : "expected iso, letter, legal, none or a ratio between 1 and "
                               "10, got '" +
                                   v + "'";
      });
  app.add_option("--better-views", o.better_views.min_gain,
                 "texture a point from another photo (--images) where it resolves the page "
                 "this many times better than the reference photo, e.g. a fold's panel the "
                 "reference sees at a grazing angle (0 = off)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  return RunStage("render", app, argc, argv, [&] {
    const auto start = std::chrono::steady_clock::now();
    o.antialias = !no_antialias;
    o.deskew = !no_deskew;
    o.orient = !no_orient;
    o.extend_cut_sides = !no_extend;
    o.texture_cut_sides = !no_texture_cut;
    o.reach_real_sides = !no_reach;
    o.page_aspect = *PageAspect(page_format);
    const render::RenderInputs in =
        render::ReadRenderInputs(sfm, boundary, meshes, images, features);
    const double read_s = SecondsSince(start);
    render::RenderResult result = render::Run(o, in);
    result.report["timing_s"]["read"] = read_s;
    const auto write_start = std::chrono::steady_clock::now();
    render::WriteRenderOutputs(out, result);
    Log("wrote " + out + "/rectified.png " + std::to_string(result.rectified.cols) + "x" +
        std::to_string(result.rectified.rows) + " (crop " + result.crop_rule + ", size " +
        result.size_rule + ", rotation " + std::to_string(result.rotation_deg) + " deg) in " +
        std::to_string(SecondsSince(start)) + " s (read " + std::to_string(read_s) + " s, write " +
        std::to_string(SecondsSince(write_start)) + " s)");
  });
}
