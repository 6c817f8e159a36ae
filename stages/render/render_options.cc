// render's command-line options, each declared once (common/option_table.h).
#include <exception>
#include <string>

#include "common/option_table.h"
#include "stages/render/render.h"

namespace docunfold::render {

std::string ParsePageFormat(const std::string& text, double* aspect) {
  if (text == "iso") {
    *aspect = kIsoAspect;
  } else if (text == "letter") {
    *aspect = kLetterAspect;
  } else if (text == "legal") {
    *aspect = kLegalAspect;
  } else if (text == "none") {
    *aspect = 0.0;
  } else {
    try {
      size_t used = 0;
      const double ratio = std::stod(text, &used);
      if (used == text.size() && ratio >= 1 && ratio <= 10) {
        *aspect = ratio;
        return "";
      }
    } catch (const std::exception&) {
    }
    return "expected iso, letter, legal, none or a ratio between 1 and 10, got '" + text + "'";
  }
  return "";
}

std::string PageFormatText(double aspect) {
  if (aspect == kIsoAspect) return "iso";
  if (aspect == kLetterAspect) return "letter";
  if (aspect == kLegalAspect) return "legal";
  if (aspect == 0) return "none";
  return Json(aspect).dump();
}

void DeclareOptions(OptionTable& table, RenderOptions* o) {
  CLI::Option* width = table.Value("width", &o->width,
                                   "output width (px; default: keep the reference image's pixel "
                                   "density on the page)");
  CLI::Option* height = table.Value("height", &o->height, "output height (px)");
  CLI::Option* dpi =
      table.Value("dpi", &o->dpi, "dots per inch; needs --page-width-mm or --page-height-mm");
  CLI::Option* scale = table.Value("scale", &o->scale,
                                   "multiple of the reference image's pixel density on the page");
  width->excludes(height, dpi, scale);
  height->excludes(dpi, scale);
  dpi->excludes(scale);
  CLI::Option* page_width = table.Value("page-width-mm", &o->page_width_mm,
                                        "physical width of the crop (mm; the page's width when its "
                                        "left and right sides are real), for --dpi");
  CLI::Option* page_height = table.Value("page-height-mm", &o->page_height_mm,
                                         "physical height of the crop (mm), for --dpi");
  page_width->excludes(page_height);
  table.Value("max-pixels", &o->max_pixels, "cap on width*height (pixels)");
  table.Value("fill", &o->fill,
              "colour where the crop shows no visible page: paper (median page colour), white or "
              "#RRGGBB");
  table.Switch("orient", &o->orient,
               "turn the page so that its text reads upright (Tesseract decides which way up); "
               "off: keep the page as M' has it, even if its text reads sideways or upside down");
  table.Switch("antialias", &o->antialias,
               "pre-filter the reference image when minifying; off: plain bicubic");
  table.Switch("deskew", &o->deskew,
               "turn M' by the small angle that makes the page's lines axis aligned");
  table.Choice("deskew-by", &o->deskew_by,
               {{"lines", DeskewBy::kLines}, {"sides", DeskewBy::kSides}},
               "lines: the direction most of optimize's lines (lines.json beside the meshes) "
               "follow, else the sides; sides: the real boundary sides");
  table.Value("max-deskew-deg", &o->max_deskew_deg, "largest tilt corrected (degrees)");
  table.Value("side-snap", &o->side_snap,
              "boundary samples up to this far outside M (fraction of the image diagonal) are "
              "mapped onto the plane of the nearest face");
  table.Choice("texture", &o->texture,
               {{"fusion", Texture::kFusion}, {"reference", Texture::kReference}},
               "fusion: each part of the page from the photo that sees it best (levelled, "
               "registered, seams where the photos agree); reference: the reference photo alone, "
               "as the paper renders it");
  table.Value("reference-preference", &o->fusion.reference_preference, 1.0, 100.0,
              "fusion: another photo colours a part of the page only where it resolves it this "
              "many times more finely than the reference photo");
  table.Switch("sample-hidden", &o->sample_hidden,
               "sample the reference image also where it does not see the page");
  table.Choice("shading", &o->shading, {{"keep", Shading::kKeep}, {"remove", Shading::kRemove}},
               "remove: divide out the light's shading (folds, curls, shadows) so that the paper "
               "comes out one even colour, as from a scanner (far better OCR); keep: the "
               "reference photo's brightness, as the paper's method renders it");
  table.Value("page-rim-px", &o->page_edge.mixed_px, 0, 20,
              "pixels just inside each photo's page outline, mixed with the table by lens blur, "
              "are replaced by the page's colour continued from further inside before the "
              "texture is sampled (0: the photos as they are)");
  table.Switch("straighten", &o->straighten.enabled,
               "straighten the printed rows and columns in the finished image where M' left them "
               "a little wavy (off: the image as M' maps it)");
  table.Switch(
      "texture-cut-sides", &o->texture_cut_sides,
      "texture the page found past a cut side from the other views that see it (--images); "
      "off: the fill colour");
  table.Switch("reach-real-sides", &o->reach_real_sides,
               "where M stops short of a real side (a blank margin with no points), continue M to "
               "the side's outline; off: crop where M stops");
  table.Value("reach-partial-below", &o->reach_partial_below, 0.0, 1.0,
              "also reach a real side of which fewer than this fraction of the samples map onto M "
              "(they are only where M gets to it), and crop at the farther of its line and the "
              "reached edge (0 = only sides too short to fit)");
  table.Value("edge-on-cos", &o->edge_on_sides.max_cos, 0.0, 1.0,
              "a real side along which the reference photo's rays meet M at |cos| below this "
              "(0.5: within 30 degrees of the surface) is placed from the other photo that "
              "sees M there most squarely (0: every side from the reference photo)");
  table.Value("warp-max-slant-deg", &o->warp_max_slant_deg, 0.0, 45.0,
              "warp the page so that the boundary sides' lines in M' within this many degrees of "
              "their axes become the crop's edges (0: inscribe the crop in the lines)");
  table.Switch("extend-cut-sides", &o->extend_cut_sides,
               "where the reference image cuts the page off, look for the page edge past it in the "
               "other views' page masks (<boundary>/views/*/mask.png) and extend the crop to it; "
               "off: stop the crop there");
  table.Value("max-extension", &o->cut_sides.max_extension, 0.0, 10.0,
              "how far past a cut side the page edge is looked for, as a fraction of what the "
              "reference view shows along that axis");
  table.Parsed<double>(
      "page-format", &o->page_aspect, "iso|letter|legal|none|RATIO", ParsePageFormat,
      PageFormatText,
      "where the page is cut off and no photo sees its edge, lengthen the crop across the cut to "
      "the whole page of this format, the unseen part in the fill colour: iso (A4, A5, ...: sides "
      "1:1.414), letter (1:1.294), legal (1:1.647), a long-to-short ratio such as 1.5, or none "
      "(stop where the photos do)");
}

}  // namespace docunfold::render
