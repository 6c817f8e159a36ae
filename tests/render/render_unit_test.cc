// render on analytic scenes whose exact result is known: a textured page,
// flat or bent into a cylinder, seen by one camera.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/json_io.h"
#include "stages/render/crop.h"
#include "stages/render/cut_sides.h"
#include "stages/render/render.h"
#include "tests/render/render_fixtures.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

// The texture as the rendering should show it: the crop of the page,
// resized (area filter) to the output size.
cv::Mat ExpectedImage(const SyntheticScene& s, const render::RenderResult& r) {
  const double px_per_unit = s.texture.cols / s.page_w;
  const cv::Rect2d crop(r.crop_x0 * px_per_unit, r.crop_y0 * px_per_unit,
                        (r.crop_x1 - r.crop_x0) * px_per_unit,
                        (r.crop_y1 - r.crop_y0) * px_per_unit);
  // Area-resample the crop: map output pixels to texture with an affine
  // warp after pre-smoothing by the scale factor.
  const double f = r.pixels_per_unit / px_per_unit;  // output px per texture px
  cv::Mat small;
  cv::resize(s.texture, small, cv::Size(), f, f, cv::INTER_AREA);
  const double ax = double(s.texture.cols) / small.cols * f;  // ~1
  const cv::Matx23d out_to_small(1 / ax, 0, crop.x * f / ax + 0.5 / ax - 0.5, 0, 1 / ax,
                                 crop.y * f / ax + 0.5 / ax - 0.5);
  cv::Mat out;
  cv::warpAffine(small, out, out_to_small, r.rectified.size(),
                 cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
  return out;
}

double MeanAbsGreyDifference(const cv::Mat& a, const cv::Mat& b, const cv::Mat1b& mask) {
  cv::Mat ga, gb, diff;
  cv::cvtColor(a, ga, cv::COLOR_BGR2GRAY);
  cv::cvtColor(b, gb, cv::COLOR_BGR2GRAY);
  cv::absdiff(ga, gb, diff);
  return cv::mean(diff, mask)[0];
}

void Keep(const std::string& name, const cv::Mat& image) {
  if (std::getenv("DOCUNFOLD_KEEP_TEST_DIRS"))
    cv::imwrite("/tmp/render-unit-" + name + ".png", image);
}

cv::Mat1b Inner(const cv::Mat1b& mask, int margin) {
  cv::Mat1b out;
  cv::erode(mask, out, cv::Mat(), cv::Point(-1, -1), margin);
  return out;
}

TEST(RenderScene, BentPageReproducesItsTexture) {
  const SyntheticScene s = MakeScene({});
  const render::RenderResult r = render::Run({}, InputsOf(s));
  EXPECT_EQ(r.crop_rule, "boundary-lines");
  const double px = 1 / r.pixels_per_unit;
  EXPECT_NEAR(r.crop_x0, 0, px);
  EXPECT_NEAR(r.crop_y0, 0, px);
  EXPECT_NEAR(r.crop_x1, s.page_w, px);
  EXPECT_NEAR(r.crop_y1, s.page_h, px);
  EXPECT_NEAR(r.rotation_deg, 0, 0.02);
  EXPECT_EQ(r.hidden_fraction, 0);
  EXPECT_GT(r.page_fraction, 0.99);
  const cv::Mat expected = ExpectedImage(s, r);
  const cv::Mat1b mask = Inner(r.page_mask, 3);
  const cv::Mat1f a = Detail(expected), b = Detail(r.rectified);
  EXPECT_GT(Correlation(a, b, mask), 0.9);
  const TileOffsets off = FindTileOffsets(a, b, mask, 32, 6);
  ASSERT_GT(off.tiles, 10);
  EXPECT_EQ(off.matched, off.tiles);
  EXPECT_LT(off.median, 0.3);
  EXPECT_LT(off.max, 1.0);
  EXPECT_LT(MeanAbsGreyDifference(expected, r.rectified, mask), 12);
  // The grid overlay is the same picture with lines on it.
  ASSERT_EQ(r.rectified_grid.size(), r.rectified.size());
  cv::Mat diff;
  cv::absdiff(r.rectified_grid, r.rectified, diff);
  cv::cvtColor(diff, diff, cv::COLOR_BGR2GRAY);
  const double changed = cv::countNonZero(diff > 30) / double(diff.total());
  EXPECT_GT(changed, 0.02);
  EXPECT_LT(changed, 0.5);
}

// The outermost ring of output pixels, `width` pixels wide.
cv::Mat1b Rim(cv::Size size, int width) {
  cv::Mat1b rim(size, uchar(255));
  rim(cv::Rect(width, width, size.width - 2 * width, size.height - 2 * width)).setTo(0);
  return rim;
}

TEST(RenderScene, TheTableDoesNotShowAlongTheCropsEdges) {
  // A lens's blur mixes the page's outermost pixels with the green table.
  SceneOptions o;
  o.radius = 0;
  o.tilt_deg = 10;
  SyntheticScene s = MakeScene(o);
  cv::GaussianBlur(s.photo, s.photo, cv::Size(), 1.0);
  auto rim_error = [&](int mixed_px) {
    render::RenderOptions options;
    options.page_edge.mixed_px = mixed_px;
    const render::RenderResult r = render::Run(options, InputsOf(s));
    Keep("rim-" + std::to_string(mixed_px), r.rectified);
    // Where the page is blank paper at its edge (the text runs off its right side).
    const cv::Mat expected = ExpectedImage(s, r);
    cv::Mat1b paper;
    cv::cvtColor(expected, paper, cv::COLOR_BGR2GRAY);
    const cv::Mat1b rim = Rim(r.rectified.size(), 1) & (paper > 230);
    EXPECT_GT(cv::countNonZero(rim), r.rectified.rows);
    return MeanAbsGreyDifference(expected, r.rectified, rim);
  };
  const double continued = rim_error(render::PageEdgeOptions{}.mixed_px);
  const double as_photographed = rim_error(0);
  EXPECT_LT(continued, 6);
  EXPECT_GT(as_photographed, 5 * continued);
}

TEST(PageEdge, TheRimTakesThePagesColourAndTheRestIsKept) {
  // Paper with a gradient, on a dark table, blurred: a mixed rim.
  cv::Mat3b photo(120, 160, cv::Vec3b(30, 40, 50));
  const cv::Rect page(30, 20, 100, 80);
  for (int y = page.y; y < page.br().y; ++y)
    for (int x = page.x; x < page.br().x; ++x)
      photo(y, x) = cv::Vec3b(uchar(180 + (x - page.x) / 2), 210, 220);
  cv::Mat3b blurred;
  cv::GaussianBlur(photo, blurred, cv::Size(), 1.0);
  cv::Mat1b mask(photo.size(), uchar(0));
  mask(page).setTo(255);
  const render::PageEdgeOptions options;
  const cv::Mat3b out = render::ContinuePageColour(blurred, mask, options);
  ASSERT_EQ(out.size(), photo.size());
  // Deep inside and far outside: untouched.
  for (const cv::Point p :
       {cv::Point(80, 60), cv::Point(40, 30), cv::Point(5, 5), cv::Point(155, 115)})
    EXPECT_EQ(out(p), blurred(p)) << p;
  // On the outline, and up to reach_px past it: the paper's colour nearby.
  for (const cv::Point p :
       {cv::Point(30, 60), cv::Point(129, 60), cv::Point(80, 20), cv::Point(80, 99),
        cv::Point(80, 99 + options.reach_px - 2), cv::Point(30 - options.reach_px + 2, 60)}) {
    const cv::Point inside(std::clamp(p.x, page.x + 4, page.br().x - 5),
                           std::clamp(p.y, page.y + 4, page.br().y - 5));
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(out(p)[c], photo(inside)[c], 6) << p << " channel " << c;
  }
  // Off: the photo itself.
  const cv::Mat off = render::ContinuePageColour(blurred, mask, {.mixed_px = 0});
  EXPECT_EQ(off.data, blurred.data);
}

TEST(PageEdge, APageCutOffByTheImageKeepsItsPixelsThere) {
  cv::Mat3b photo(100, 100, cv::Vec3b(200, 200, 200));
  cv::Mat1b mask(photo.size(), uchar(0));
  mask(cv::Rect(0, 0, 60, 100)).setTo(255);  // the page runs off the left, top and bottom
  for (int y = 0; y < 100; ++y) photo(y, 0) = cv::Vec3b(0, 0, 255);  // print at the cut
  const cv::Mat3b out = render::ContinuePageColour(photo, mask, render::PageEdgeOptions{});
  for (int y = 0; y < 100; ++y) EXPECT_EQ(out(y, 0), cv::Vec3b(0, 0, 255)) << y;
  EXPECT_EQ(out(0, 30), photo(0, 30));
  EXPECT_EQ(out(99, 30), photo(99, 30));
}

TEST(RenderScene, DefaultSizeKeepsTheReferenceDensity) {
  // A frontal flat page at depth 1: f pixels per unit everywhere.
  SceneOptions o;
  o.radius = 0;
  o.tilt_deg = 0;
  o.focal = 500;
  o.page_origin = {-0.2, -0.25, 1.0};
  o.page_w = 0.4;
  o.page_h = 0.5;
  const SyntheticScene s = MakeScene(o);
  const render::RenderResult r = render::Run({}, InputsOf(s));
  EXPECT_NEAR(r.reference_pixels_per_unit, 500, 0.5);
  EXPECT_NEAR(r.pixels_per_unit, 500, 1.0);
  EXPECT_NEAR(r.rectified.cols, 0.4 * 500, 1);
  EXPECT_NEAR(r.rectified.rows, 0.5 * 500, 1);
  EXPECT_EQ(r.size_rule, "reference-density");
  // Frontal at the same density: neither magnified nor minified.
  EXPECT_LT(r.minified_fraction, 0.01);
}

// The output size rounds the crop to whole pixels; the crop itself stays
// where the page's sides put it, so whatever the size, the image's edges are
// the same lines of M'.
TEST(RenderScene, TheCropDoesNotMoveWithTheOutputSize) {
  const SyntheticScene s = MakeScene({});
  const render::RenderInputs in = InputsOf(s);
  const render::RenderResult plain = render::Run({}, in);
  for (const int width : {101, 250, 333}) {
    render::RenderOptions o;
    o.width = width;
    const render::RenderResult r = render::Run(o, in);
    ASSERT_EQ(r.rectified.cols, width);
    EXPECT_NEAR(r.crop_x0, plain.crop_x0, 1e-9) << width;
    EXPECT_NEAR(r.crop_x1, plain.crop_x1, 1e-9) << width;
    EXPECT_NEAR(r.crop_y0, plain.crop_y0, 1e-9) << width;
    EXPECT_NEAR(r.crop_y1, plain.crop_y1, 1e-9) << width;
    EXPECT_NEAR((r.crop_x1 - r.crop_x0) * r.pixels_per_unit, r.rectified.cols, 1e-6);
    EXPECT_NEAR((r.crop_y1 - r.crop_y0) * r.pixels_per_unit_y, r.rectified.rows, 1e-6);
    // Pixels square to within the half pixel the height was rounded by.
    EXPECT_NEAR(r.pixels_per_unit_y, r.pixels_per_unit, r.pixels_per_unit / r.rectified.rows);
  }
}

TEST(RenderScene, SizeOptions) {
  const SyntheticScene s = MakeScene({});
  const render::RenderInputs in = InputsOf(s);
  const double aspect = s.page_w / s.page_h;
  {
    render::RenderOptions o;
    o.width = 300;
    const auto r = render::Run(o, in);
    EXPECT_EQ(r.rectified.cols, 300);
    EXPECT_NEAR(r.rectified.rows, 300 / aspect, 1.0);
    EXPECT_EQ(r.size_rule, "width");
  }
  {
    render::RenderOptions o;
    o.height = 200;
    const auto r = render::Run(o, in);
    EXPECT_EQ(r.rectified.rows, 200);
    EXPECT_NEAR(r.rectified.cols, 200 * aspect, 1.0);
  }
  {
    render::RenderOptions o;
    o.dpi = 50;
    o.page_width_mm = 210;
    const auto r = render::Run(o, in);
    EXPECT_NEAR(r.rectified.cols, 210 / 25.4 * 50, 1.0);
    EXPECT_EQ(r.size_rule, "dpi");
  }
  {
    render::RenderOptions o;
    o.scale = 0.5;
    const auto r = render::Run(o, in);
    // Within the half pixel the crop's width is rounded by.
    EXPECT_NEAR(r.pixels_per_unit, 0.5 * r.reference_pixels_per_unit,
                r.pixels_per_unit / r.rectified.cols);
    EXPECT_NEAR(r.pixels_per_unit_y, 0.5 * r.reference_pixels_per_unit,
                r.pixels_per_unit_y / r.rectified.rows);
  }
  {
    render::RenderOptions o;
    o.max_pixels = 20000;
    const auto r = render::Run(o, in);
    EXPECT_TRUE(r.capped);
    EXPECT_LE(r.rectified.total(), 20000u);
    EXPECT_GT(r.rectified.total(), 19000u);
  }
  render::RenderOptions both;
  both.width = 100;
  both.scale = 2;
  EXPECT_THROW(render::Run(both, in), UsageError);
  render::RenderOptions dpi_alone;
  dpi_alone.dpi = 300;
  EXPECT_THROW(render::Run(dpi_alone, in), UsageError);
  render::RenderOptions too_big;
  too_big.width = 100000;
  EXPECT_THROW(render::Run(too_big, in), UsageError);
  render::RenderOptions bad_fill;
  bad_fill.fill = "#12345";
  EXPECT_THROW(render::Run(bad_fill, in), UsageError);
  render::RenderOptions hex_fill;
  hex_fill.fill = "#102030";
  EXPECT_EQ(render::Run(hex_fill, in).fill, cv::Vec3b(0x30, 0x20, 0x10));
}

TEST(RenderScene, MinifyingFiltersTheFootprint) {
  // The page at a slant, rendered at a third of its density: fine stripes
  // and text must come out as their area average, not as moire.
  const SyntheticScene s = MakeScene({});
  const render::RenderInputs in = InputsOf(s);
  render::RenderOptions o;
  o.scale = 1.0 / 3;
  const auto filtered = render::Run(o, in);
  o.antialias = false;
  const auto aliased = render::Run(o, in);
  ASSERT_EQ(filtered.rectified.size(), aliased.rectified.size());
  EXPECT_GT(filtered.minified_fraction, 0.9);
  EXPECT_EQ(aliased.minified_fraction, 0);
  const cv::Mat expected = ExpectedImage(s, filtered);
  const cv::Mat1b mask = Inner(filtered.page_mask, 2);
  const double err_filtered = MeanAbsGreyDifference(expected, filtered.rectified, mask);
  const double err_aliased = MeanAbsGreyDifference(expected, aliased.rectified, mask);
  // What an area resize of the full-density rendering achieves: the best
  // the blur already in the photo allows.
  const auto full = render::Run({}, in);
  cv::Mat area;
  cv::resize(full.rectified, area, filtered.rectified.size(), 0, 0, cv::INTER_AREA);
  const double err_area = MeanAbsGreyDifference(expected, area, mask);
  std::printf(
      "minify: mean |grey difference| filtered %.2f, aliased %.2f, area resize "
      "%.2f\n",
      err_filtered, err_aliased, err_area);
  EXPECT_LT(err_filtered, 1.15 * err_area);
  EXPECT_LT(err_filtered, 0.7 * err_aliased);
}

TEST(RenderScene, CutOffPageIsCroppedByItsRealSidesAndWhatTheViewSees) {
  SceneOptions o;
  o.page_origin = {-0.6, -0.3, 1.0};  // the left part runs off the image
  const SyntheticScene s = MakeScene(o);
  ASSERT_FALSE(s.real[3]);
  ASSERT_TRUE(s.real[0] && s.real[1] && s.real[2]);
  const render::RenderResult r = render::Run({}, InputsOf(s));
  EXPECT_EQ(r.crop_rule, "real-sides-and-visible-mesh");
  EXPECT_FALSE(r.page_format.applied);
  EXPECT_FALSE(r.sides[3].used);
  EXPECT_TRUE(r.sides[0].used);
  EXPECT_TRUE(r.sides[1].used);
  EXPECT_TRUE(r.sides[2].used);
  // The image's left border meets the flat part of the page at
  // a = k z - x_origin with k = (-0.5 - cx) / f, farthest (largest z) at the
  // bottom row: that is where the seen part of M' begins.
  const double tilt = o.tilt_deg * M_PI / 180;
  const double k = (-0.5 - s.camera.K(0, 2)) / s.camera.K(0, 0);
  const double x0 = k * (o.page_origin.z() + o.page_h * std::sin(tilt)) - o.page_origin.x();
  const double px = 1 / r.pixels_per_unit;
  EXPECT_NEAR(r.crop_x0, x0, 2 * px);
  EXPECT_NEAR(r.crop_x1, s.page_w, px);
  EXPECT_NEAR(r.crop_y0, 0, px);
  EXPECT_NEAR(r.crop_y1, s.page_h, px);
  // Unseen corners of the crop get the fill (the median page colour).
  EXPECT_GT(r.hidden_fraction, 0.005);
  EXPECT_NEAR(r.page_fraction + r.hidden_fraction, 1.0, 0.01);
  const cv::Vec3b paper = r.fill;
  EXPECT_GT(paper[0], 200);
  for (int y = 0; y < r.rectified.rows; y += 7)
    for (int x = 0; x < r.rectified.cols; x += 7) {
      if (!r.page_mask(y, x)) {
        ASSERT_EQ(r.rectified.at<cv::Vec3b>(y, x), paper);
      }
    }
  // The seen part is still the texture (mostly the bent half, seen at a
  // slant and so blurred in the photo).
  Keep("cutoff", r.rectified_grid);
  const cv::Mat1b mask = Inner(r.page_mask, 3);
  const cv::Mat1f a = Detail(ExpectedImage(s, r)), b = Detail(r.rectified);
  EXPECT_GT(Correlation(a, b, mask), 0.8);
  const TileOffsets off = FindTileOffsets(a, b, mask, 32, 6);
  ASSERT_GT(off.tiles, 5);
  EXPECT_EQ(off.matched, off.tiles);
  EXPECT_LT(off.median, 0.5);
}

TEST(RenderScene, APageCutOffUnseenIsCompletedToItsFormat) {
  SceneOptions o;
  o.page_origin = {-0.6, -0.3, 1.0};  // the left part runs off the image
  const SyntheticScene s = MakeScene(o);
  ASSERT_FALSE(s.real[3]);
  render::RenderOptions options;
  options.page_aspect = o.page_h / o.page_w;  // the scene's page, 0.56 x 0.42
  const render::RenderResult r = render::Run(options, InputsOf(s));
  ASSERT_TRUE(r.page_format.applied);
  EXPECT_EQ(r.page_format.axis, 0);
  const double px = 1 / r.pixels_per_unit;
  // The whole page, its unseen left part in the fill colour.
  EXPECT_NEAR(r.crop_x0, 0, 2 * px);
  EXPECT_NEAR(r.crop_x1, s.page_w, px);
  EXPECT_NEAR(r.crop_y0, 0, px);
  EXPECT_NEAR(r.crop_y1, s.page_h, px);
  EXPECT_EQ(r.rectified.at<cv::Vec3b>(r.rectified.rows / 2, 2), r.fill);
  const Json report = render::RenderReport(options, InputsOf(s), r, Json::object());
  EXPECT_EQ(report["page_format"]["applied"], true);
  EXPECT_EQ(report["page_format"]["axis"], "x");
  // ISO: the part seen is narrower than 0.56 / 1.414, so the page is taken
  // to be that wide (its long side up).
  ASSERT_LT(r.page_format.seen, s.page_h / render::kIsoAspect);
  options.page_aspect = render::kIsoAspect;
  const render::RenderResult iso = render::Run(options, InputsOf(s));
  ASSERT_TRUE(iso.page_format.applied);
  EXPECT_NEAR(iso.crop_x1 - iso.crop_x0, s.page_h / render::kIsoAspect, 2 * px);
  EXPECT_NEAR(iso.crop_x1, s.page_w, px);
}

TEST(RenderScene, APageCutOffOnBothAxesKeepsItsCropAndSaysWhy) {
  SceneOptions o;
  o.page_origin = {-0.6, -0.55, 1.0};  // the left and top parts run off the image
  const SyntheticScene s = MakeScene(o);
  ASSERT_FALSE(s.real[3]);
  ASSERT_FALSE(s.real[0]);
  const render::RenderResult plain = render::Run({}, InputsOf(s));
  render::RenderOptions options;
  options.page_aspect = render::kIsoAspect;
  const render::RenderResult r = render::Run(options, InputsOf(s));
  EXPECT_FALSE(r.page_format.applied);
  EXPECT_EQ(r.crop_x0, plain.crop_x0);
  EXPECT_EQ(r.crop_y0, plain.crop_y0);
  const Json report = render::RenderReport(options, InputsOf(s), r, Json::object());
  ASSERT_TRUE(report.contains("page_format"));
  EXPECT_EQ(report["page_format"]["axis"], "both");
  EXPECT_EQ(report["page_format"]["applied"], false);
  EXPECT_FALSE(report["page_format"]["note"].get<std::string>().empty());
}

TEST(RenderOptions, PageFormatIsANameOrARatio) {
  double aspect = -1;
  EXPECT_EQ(render::ParsePageFormat("iso", &aspect), "");
  EXPECT_EQ(aspect, render::kIsoAspect);
  EXPECT_EQ(render::ParsePageFormat("letter", &aspect), "");
  EXPECT_EQ(aspect, render::kLetterAspect);
  EXPECT_EQ(render::ParsePageFormat("legal", &aspect), "");
  EXPECT_EQ(aspect, render::kLegalAspect);
  EXPECT_EQ(render::ParsePageFormat("1.5", &aspect), "");
  EXPECT_EQ(aspect, 1.5);
  EXPECT_EQ(render::ParsePageFormat("none", &aspect), "");
  EXPECT_EQ(aspect, 0);
  for (const char* bad : {"a3", "0.7", "11", "1.5x", ""})
    EXPECT_NE(render::ParsePageFormat(bad, &aspect), "") << bad;
  EXPECT_EQ(aspect, 0);  // left as it was
  for (const char* text : {"iso", "letter", "legal", "none", "1.5"}) {
    ASSERT_EQ(render::ParsePageFormat(text, &aspect), "");
    EXPECT_EQ(render::PageFormatText(aspect), text);
  }
}

TEST(RenderCrop, TheFormatLengthensOnlyUnseenSidesOfOneAxis) {
  const double a = render::kIsoAspect;
  auto crop = [](double w, double h) { return render::CropRect{0, 0, w, h, "test"}; };
  // Right side unseen, 1 high: the page seen (0.5 wide) is the short side,
  // 1 / 1.414 = 0.707 wide.
  render::CropRect c = crop(0.5, 1);
  render::PageFormatFit f = render::ExtendToPageFormat(&c, {false, true, false, false}, a);
  EXPECT_TRUE(f.applied);
  EXPECT_EQ(f.axis, 0);
  EXPECT_NEAR(c.x1, 1 / a, 1e-12);
  EXPECT_EQ(c.x0, 0);
  EXPECT_EQ(c.y1, 1);
  // 0.8 wide seen: more than the short side, so the long one, 1.414.
  c = crop(0.8, 1);
  f = render::ExtendToPageFormat(&c, {false, true, false, false}, a);
  EXPECT_TRUE(f.applied);
  EXPECT_NEAR(c.x1, a, 1e-12);
  EXPECT_NEAR(f.length, a, 1e-12);
  // Top and bottom unseen: they share the lengthening.
  c = crop(1, 1.2);
  f = render::ExtendToPageFormat(&c, {true, false, true, false}, a);
  EXPECT_TRUE(f.applied);
  EXPECT_EQ(f.axis, 1);
  EXPECT_NEAR(c.y0, -0.5 * (a - 1.2), 1e-12);
  EXPECT_NEAR(c.y1, 1.2 + 0.5 * (a - 1.2), 1e-12);
  // Already the format's length (within 1 %): left as it is.
  c = crop(1.42, 1);
  f = render::ExtendToPageFormat(&c, {false, false, false, true}, a);
  EXPECT_FALSE(f.applied);
  EXPECT_TRUE(f.note.empty());
  EXPECT_EQ(c.x0, 0);
  // Longer than any page of that format: not this format, left, with a note.
  c = crop(1.6, 1);
  f = render::ExtendToPageFormat(&c, {false, true, false, false}, a);
  EXPECT_FALSE(f.applied);
  EXPECT_FALSE(f.note.empty());
  EXPECT_EQ(c.x1, 1.6);
  // Both axes cut off unseen: the width is not known.
  c = crop(0.5, 0.5);
  f = render::ExtendToPageFormat(&c, {true, true, false, false}, a);
  EXPECT_FALSE(f.applied);
  EXPECT_FALSE(f.note.empty());
  EXPECT_EQ(c.x1, 0.5);
  EXPECT_EQ(c.y0, 0);
  // Nothing unseen: nothing to do.
  c = crop(0.5, 1);
  f = render::ExtendToPageFormat(&c, {false, false, false, false}, a);
  EXPECT_FALSE(f.applied);
  EXPECT_EQ(f.axis, -1);
  EXPECT_EQ(c.x1, 0.5);
}

TEST(RenderScene, PartsTheReferenceViewCannotSeeAreFilled) {
  // The right half rolls into a tube: much of it faces away from the camera
  // or hides behind itself.
  SceneOptions o;
  o.radius = 0.05;
  SyntheticScene s = MakeScene(o);
  // The outline of the page region: the roll is no page edge, so the right
  // side is not real, and only the flat halves of the top and bottom are.
  s.real[1] = false;
  s.sides[0].resize(s.sides[0].size() / 2);
  s.sides[2].resize(s.sides[2].size() / 2);
  const render::RenderInputs in = InputsOf(s);
  const render::RenderResult r = render::Run({}, in);
  EXPECT_GT(r.hidden_fraction, 0.2);
  Keep("tube", r.rectified_grid);
  // The flat half, seen directly, is intact.
  cv::Mat1b left = cv::Mat1b::zeros(r.page_mask.size());
  left(cv::Rect(0, 0, int(r.rectified.cols * 0.45), r.rectified.rows)).setTo(255);
  const cv::Mat1b mask = Inner(r.page_mask, 3) & left;
  EXPECT_GT(cv::countNonZero(mask), 0.3 * mask.total());
  EXPECT_GT(Correlation(Detail(ExpectedImage(s, r)), Detail(r.rectified), mask), 0.9);
  // Sides drawn over the roll map onto other parts of M: they must not tilt
  // or cut the crop.
  SyntheticScene full = MakeScene(o);
  full.real[1] = false;
  const render::RenderResult outline = render::Run({}, InputsOf(full));
  EXPECT_LT(std::abs(outline.rotation_deg), 0.25);
  EXPECT_NEAR(outline.crop_y0, 0, 1 / outline.pixels_per_unit);
  EXPECT_NEAR(outline.crop_y1, o.page_h, 1 / outline.pixels_per_unit);
  // With --sample-hidden those pixels show whatever the view has there.
  render::RenderOptions sample;
  sample.sample_hidden = true;
  const render::RenderResult all = render::Run(sample, in);
  EXPECT_GT(cv::countNonZero(all.page_mask), cv::countNonZero(r.page_mask));
}

// A real side whose samples scatter about their line (a fold on the outline,
// or M far off there) is not fitted, but the median of its samples still
// bounds the crop; the mesh may run past the page there.
TEST(RenderScene, ScatteredSideBoundsTheCropByItsMedian) {
  SceneOptions o;
  o.radius = 0;
  SyntheticScene s = MakeScene(o);
  // The outline says the page's left edge is at x = 0.05 of M' (the mesh
  // runs 0.05 past it), ragged by +-10 pixels.
  const double edge = 0.05;
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(o.tilt_deg * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  s.sides[3].clear();
  for (int k = 0; k <= 60; ++k) {
    const Eigen::Vector3d p = o.page_origin + tilt * Eigen::Vector3d(edge, o.page_h * k / 60, 0);
    s.sides[3].push_back(s.camera.Project(p) + Eigen::Vector2d(k % 2 ? 10 : -10, 0));
  }
  s.sides[0].front() = s.camera.Project(o.page_origin + tilt * Eigen::Vector3d(edge, 0, 0));
  s.sides[2].front() = s.camera.Project(o.page_origin + tilt * Eigen::Vector3d(edge, o.page_h, 0));
  render::RenderInputs in = InputsOf(s);
  in.other_references = {"view_02.jpg", "view_00.jpg"};
  const render::RenderResult r = render::Run({}, in);
  ASSERT_TRUE(r.sides[3].scattered) << r.sides[3].note;
  EXPECT_FALSE(r.sides[3].used);
  // M is likely wrong there: a warning names the side and sfm's next choice.
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("along its left side"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("REF=view_02.jpg"), std::string::npos) << r.warnings[0];
  const double px = 1 / r.pixels_per_unit;
  EXPECT_NEAR(r.crop_x0, edge, 2 * px);
  EXPECT_NEAR(r.crop_x1, o.page_w, px);
  EXPECT_NEAR(r.sides[3].median_bound, edge, 2 * px);
  EXPECT_GT(r.crop_x0, 0.5 * edge);  // not the mesh's border (x = 0)
}

// sfm's ranking of the photos as the reference, for the warning's advice:
// the others in its order; entries without a name are skipped, and a
// cameras.json without the ranking gives none.
TEST(RenderInputsFile, OtherReferencesFollowSfmsRanking) {
  TempDir dir;
  const SyntheticScene s = MakeScene({});
  WriteScene(s, dir.path());
  const fs::path sfm = dir / "10_sfm";
  const render::RenderInputs plain =
      render::ReadRenderInputs(sfm, dir / "20_boundary", dir / "40_init", "", "");
  EXPECT_TRUE(plain.other_references.empty());
  Json cameras = ReadJsonFile(sfm / "cameras.json");
  cameras["reference_selection"] = {{"method", "auto"},
                                    {"views", Json::array({{{"image", "view_09.png"}},
                                                           {{"image", s.camera.image}},
                                                           {{"score", 0.5}},
                                                           {{"image", 7}},
                                                           {{"image", "view_01.png"}}})}};
  WriteJsonAtomic(sfm / "cameras.json", cameras);
  const render::RenderInputs in =
      render::ReadRenderInputs(sfm, dir / "20_boundary", dir / "40_init", "", "");
  EXPECT_EQ(in.other_references, (std::vector<std::string>{"view_09.png", "view_01.png"}));
}

TEST(RenderScene, TiltedFlatMeshIsTurnedUpright) {
  SyntheticScene s = MakeScene({});
  const double angle = 3 * M_PI / 180;
  for (auto& q : s.meshes.mesh2d) q = Eigen::Rotation2Dd(angle) * q;
  const render::RenderResult r = render::Run({}, InputsOf(s));
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  EXPECT_NEAR(r.rotation_deg, -3, 0.05);
  EXPECT_EQ(r.crop_rule, "boundary-lines");
  EXPECT_NEAR(r.crop_x1 - r.crop_x0, s.page_w, 2 / r.pixels_per_unit);
  EXPECT_NEAR(r.crop_y1 - r.crop_y0, s.page_h, 2 / r.pixels_per_unit);
  render::RenderOptions keep;
  keep.deskew = false;
  keep.warp_max_slant_deg = 0;
  const render::RenderResult tilted = render::Run(keep, InputsOf(s));
  EXPECT_EQ(tilted.rotation_deg, 0);
  // Inscribed in the tilted page: smaller on both axes.
  EXPECT_LT(tilted.crop_x1 - tilted.crop_x0, s.page_w * 0.97);
  EXPECT_LT(tilted.crop_y1 - tilted.crop_y0, s.page_h * 0.97);
  // Warped onto the tilted sides' lines instead: the whole page, sheared.
  keep.warp_max_slant_deg = 5;
  const render::RenderResult warped = render::Run(keep, InputsOf(s));
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(warped.warped_sides[i]) << i;
  EXPECT_NEAR(warped.crop_x1 - warped.crop_x0, s.page_w, 0.01 * s.page_w);
  EXPECT_NEAR(warped.crop_y1 - warped.crop_y0, s.page_h, 0.01 * s.page_h);
  EXPECT_GT(warped.page_fraction, 0.99);
}

TEST(RenderScene, ReportGivesTheWarpBoxWheneverASideIsWarped) {
  const SyntheticScene s = MakeScene({});
  const render::RenderInputs in = InputsOf(s);
  render::RenderResult r = render::Run({}, in);
  ASSERT_TRUE(std::count(r.warped_sides.begin(), r.warped_sides.end(), true) > 0);
  auto has_box = [&] {
    return render::RenderReport({}, in, r, Json::object())["crop"].contains("warp_box");
  };
  EXPECT_TRUE(has_box());
  r.warp_max_shift = 0;  // a warp that moves no corner still maps through the box
  EXPECT_TRUE(has_box());
  r.warped_sides = {};
  EXPECT_FALSE(has_box());
}

TEST(RenderInputs, InconsistentInputsAreRejected) {
  const SyntheticScene s = MakeScene({});
  {
    render::RenderInputs in = InputsOf(s);
    for (auto& v : in.meshes.mesh3d) v.z() = -v.z();
    try {
      render::Run({}, in);
      FAIL() << "no error for a mesh behind the camera";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("behind the reference camera"), std::string::npos);
      EXPECT_NE(std::string(e.what()).find("mesh3d.ply"), std::string::npos);
    }
  }
  {
    render::RenderInputs in = InputsOf(s);
    in.boundary.width = 1600;
    EXPECT_THROW(render::Run({}, in), InputError);
  }
  {
    render::RenderInputs in = InputsOf(s);
    cv::resize(s.photo, in.reference, cv::Size(320, 240));
    EXPECT_THROW(render::Run({}, in), InputError);
  }
  {
    render::RenderInputs in = InputsOf(s);
    for (auto& v : in.meshes.mesh3d) v.x() += 10;  // far outside the view
    EXPECT_THROW(render::Run({}, in), InputError);
  }
  {
    render::RenderInputs in = InputsOf(s);
    for (auto& q : in.meshes.mesh2d) q.y() = 0;
    EXPECT_THROW(render::Run({}, in), InputError);
  }
}

TEST(RenderCrop, SideLinesIgnoreOutliersAndWrongOrderIsDropped) {
  std::vector<Eigen::Vector2d> top, bottom;
  for (int i = 0; i <= 100; ++i) {
    top.emplace_back(i * 0.01, 0.1 + 0.001 * i * 0.01);
    bottom.emplace_back(i * 0.01, 1.2);
  }
  top[50].y() += 0.2;  // a stray sample
  const render::SideFit t = render::FitSideLine(0, true, top, 101);
  EXPECT_TRUE(t.used);
  EXPECT_EQ(t.mapped, 100);
  EXPECT_LT(t.rms, 1e-9);
  EXPECT_NEAR(t.direction.y() / t.direction.x(), 0.001, 1e-9);
  EXPECT_GT(t.direction.x(), 0);
  // Too few of the samples mapped: not used.
  EXPECT_FALSE(render::FitSideLine(2, true, bottom, 1000).used);
  // Not real: never used.
  EXPECT_FALSE(render::FitSideLine(2, false, bottom, 101).used);

  std::array<render::SideFit, 4> sides;
  sides[0] = render::FitSideLine(2, true, bottom, 101);  // "top" below "bottom"
  sides[2] = render::FitSideLine(0, true, top, 101);
  render::ChooseCrop(&sides, Eigen::Vector4d(0, 0, 1, 1.3));
  EXPECT_FALSE(sides[0].used);
  EXPECT_FALSE(sides[2].used);
  EXPECT_FALSE(sides[0].note.empty());

  std::array<render::SideFit, 4> good;
  good[0] = render::FitSideLine(0, true, top, 101);
  good[2] = render::FitSideLine(2, true, bottom, 101);
  const render::CropRect crop = render::ChooseCrop(&good, Eigen::Vector4d(-0.1, 0, 1.1, 1.3));
  EXPECT_EQ(crop.rule, "real-sides-and-visible-mesh");
  EXPECT_NEAR(crop.x0, -0.1, 1e-12);
  EXPECT_NEAR(crop.x1, 1.1, 1e-12);
  EXPECT_NEAR(crop.y0, 0.1 + 0.001 * 1.1, 1e-9);  // the top line's lowest point
  EXPECT_NEAR(crop.y1, 1.2, 1e-9);
  // Weighted by the samples each line keeps (100 and 101).
  EXPECT_NEAR(render::TiltOfSides(good), std::atan(0.001) * 100 / 201, 1e-9);
}

TEST(RenderCrop, SlantedSidesBoundTheCropInscribed) {
  // The unit square's sides in M'; the right one slanted by `deg` about its
  // middle (0.5, 0.5).
  auto sides_with_right_slant = [](double deg) {
    const double t = std::tan(deg * M_PI / 180);
    std::vector<Eigen::Vector2d> top, bottom, left, right;
    for (int i = 0; i <= 100; ++i) {
      const double u = i * 0.01;
      top.emplace_back(u, 0);
      bottom.emplace_back(u, 1);
      left.emplace_back(0, u);
      right.emplace_back(1 + (u - 0.5) * t, u);
    }
    std::array<render::SideFit, 4> sides;
    sides[0] = render::FitSideLine(0, true, top, 101);
    sides[1] = render::FitSideLine(1, true, right, 101);
    sides[2] = render::FitSideLine(2, true, bottom, 101);
    sides[3] = render::FitSideLine(3, true, left, 101);
    return sides;
  };
  const Eigen::Vector4d box(-0.2, -0.2, 1.2, 1.2);
  auto slight = sides_with_right_slant(2);
  EXPECT_NEAR(render::SlantOf(slight[1], 1), -2 * M_PI / 180, 1e-9);
  const render::CropRect crop = render::ChooseCrop(&slight, box);
  EXPECT_EQ(crop.rule, "boundary-lines");
  EXPECT_NEAR(crop.x1, 1 - 0.5 * std::tan(2 * M_PI / 180), 1e-9);  // inscribed
  EXPECT_NEAR(crop.x0, 0, 1e-9);
  EXPECT_NEAR(crop.y0, 0, 1e-9);
  EXPECT_NEAR(crop.y1, 1, 1e-9);
  auto steep = sides_with_right_slant(5);
  EXPECT_NEAR(render::ChooseCrop(&steep, box).x1, 1 - 0.5 * std::tan(5 * M_PI / 180), 1e-9);
}

TEST(RenderCrop, WarpTakesSlantedSidesToTheCropEdges) {
  // Unit square whose right side runs from (1.02, 0) to (0.98, 1) and whose
  // bottom side from (0, 1) to (1, 1.03); top and left are on their axes.
  std::vector<Eigen::Vector2d> top, bottom, left, right;
  for (int i = 0; i <= 100; ++i) {
    const double u = i * 0.01;
    top.emplace_back(u, 0);
    bottom.emplace_back(u, 1 + 0.03 * u);
    left.emplace_back(0, u);
    right.emplace_back(1.02 - 0.04 * u, u);
  }
  std::array<render::SideFit, 4> sides;
  sides[0] = render::FitSideLine(0, true, top, 101);
  sides[1] = render::FitSideLine(1, true, right, 101);
  sides[2] = render::FitSideLine(2, true, bottom, 101);
  sides[3] = render::FitSideLine(3, true, left, 101);
  const render::CropRect inscribed = render::ChooseCrop(&sides, Eigen::Vector4d(-1, -1, 2, 2));
  const render::SideWarp warp = render::WarpToSides(sides, inscribed, 5 * M_PI / 180);
  ASSERT_TRUE(warp.active[0] && warp.active[1] && warp.active[2] && warp.active[3]);
  // The crop's edges are the lines where they cross the middle of the crop.
  EXPECT_NEAR(warp.crop.x1, 1.0, 1e-3);
  EXPECT_NEAR(warp.crop.y1, 1.015, 1e-3);
  // Every sample of a side lands on its crop edge; the middle of the page
  // moves by half the lines' run at most.
  for (int i = 0; i <= 100; i += 10) {
    EXPECT_NEAR(warp.Apply(right[i]).x(), warp.crop.x1, 1e-9);
    EXPECT_NEAR(warp.Apply(bottom[i]).y(), warp.crop.y1, 1e-9);
    EXPECT_NEAR(warp.Apply(left[i]).x(), warp.crop.x0, 1e-9);
    EXPECT_NEAR(warp.Apply(top[i]).y(), warp.crop.y0, 1e-9);
  }
  EXPECT_LT((warp.Apply({0.5, 0.5}) - Eigen::Vector2d(0.5, 0.5)).norm(), 0.011);
  EXPECT_NEAR(warp.max_shift, std::hypot(0.02, 0.015), 1e-3);  // the bottom-right corner
  // A side past the slant limit stays inscribed (its edge not warped).
  const render::SideWarp some = render::WarpToSides(sides, inscribed, 2 * M_PI / 180);
  EXPECT_FALSE(some.active[1]);  // 2.3 degrees
  EXPECT_TRUE(some.active[2]);   // 1.7 degrees
  EXPECT_NEAR(some.crop.x1, inscribed.x1, 1e-12);
  EXPECT_NEAR(some.Apply({inscribed.x1, 0.3}).x(), inscribed.x1, 1e-12);
  // No side used: the identity.
  const render::SideWarp none = render::WarpToSides({}, inscribed, 5 * M_PI / 180);
  EXPECT_EQ((none.Apply({0.3, 0.7}) - Eigen::Vector2d(0.3, 0.7)).norm(), 0);
}

// The columns of a scene's grid that the reference view sees whole: M and M'
// as the pipeline has them when the image cuts the page off on the left.
MeshPair SeenColumns(const SyntheticScene& s) {
  const QuadGrid& g = s.meshes.grid;
  int first = 0;
  for (int c = 0; c < g.nx; ++c) {
    bool inside = true;
    for (int r = 0; r < g.ny && inside; ++r)
      inside = s.camera.Project(s.meshes.mesh3d[g.Index(r, c)]).x() >= 0;
    if (inside) {
      first = c;
      break;
    }
  }
  MeshPair m;
  m.grid = {g.nx - first, g.ny};
  for (int r = 0; r < g.ny; ++r)
    for (int c = first; c < g.nx; ++c) {
      m.mesh3d.push_back(s.meshes.mesh3d[g.Index(r, c)]);
      m.mesh2d.push_back(s.meshes.mesh2d[g.Index(r, c)]);
    }
  return m;
}

// Another view of the same page: `other` is the scene made with the page
// moved (the same tilt), i.e. the camera moved the other way. Its page mask
// is where its raster shows the page.
render::ViewMask OtherView(const SyntheticScene& reference_scene, const SceneOptions& reference,
                           const SyntheticScene& other, const SceneOptions& other_options) {
  render::ViewMask view;
  view.camera = other.camera;
  view.camera.image = "view_01.png";
  view.camera.t = other_options.page_origin - reference.page_origin;
  const RasterResult raster =
      RasterizeMesh(other.camera, other.meshes.mesh3d, other.meshes.grid.Triangles());
  view.mask = raster.face >= 0;
  (void)reference_scene;
  return view;
}

Eigen::Vector4d BoxOf(const std::vector<Eigen::Vector2d>& flat) {
  Eigen::Vector2d lo = flat[0], hi = flat[0];
  for (const auto& q : flat) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  return {lo.x(), lo.y(), hi.x(), hi.y()};
}

TEST(RenderCutSides, AnotherViewFindsThePageEdgePastTheReferenceImage) {
  SceneOptions o;
  o.page_origin = {-0.6, -0.3, 1.0};  // the left part runs off the image
  o.radius = 0;
  const SyntheticScene s = MakeScene(o);
  ASSERT_FALSE(s.real[3]);
  const MeshPair seen = SeenColumns(s);
  const Eigen::Vector4d box = BoxOf(seen.mesh2d);
  ASSERT_GT(box[0], 0.1 * o.page_w);  // a good part of the page is cut off
  SceneOptions far = o;
  far.page_origin = {-0.25, -0.3, 1.6};  // seen whole from farther back
  const SyntheticScene s2 = MakeScene(far);
  ASSERT_TRUE(s2.real[0] && s2.real[1] && s2.real[2] && s2.real[3]);
  const std::vector<render::ViewMask> views = {OtherView(s, o, s2, far)};
  const std::array<bool, 4> cut = {false, false, false, true};

  const auto edges = render::FindCutSideEdges(seen, seen.mesh2d, box, cut, views, {});
  const render::CutSideEdge& left = edges[3];
  ASSERT_TRUE(left.measured) << left.note;
  EXPECT_TRUE(left.edge_seen);
  EXPECT_NEAR(left.bound, 0.0, 0.005 * o.page_w);  // the true left edge: x = 0
  EXPECT_NEAR(left.extension, box[0], 0.005 * o.page_w);
  EXPECT_GT(left.crossings, seen.grid.ny / 2);
  EXPECT_EQ(left.strip.cols, seen.grid.ny);
  EXPECT_FALSE(edges[0].measured || edges[1].measured || edges[2].measured);

  // A view whose own frame cuts the page before its edge: the page reaches
  // at least as far as it sees, and no farther is claimed.
  SyntheticScene s3 = s2;
  s3.camera.K(0, 2) -= 240;  // the page's left edge now lies off this photo
  const std::vector<render::ViewMask> short_views = {OtherView(s, o, s3, far)};
  ASSERT_LT(s3.camera.Project(s3.meshes.mesh3d[0]).x(), 0);
  const auto short_edges = render::FindCutSideEdges(seen, seen.mesh2d, box, cut, short_views, {});
  ASSERT_TRUE(short_edges[3].measured) << short_edges[3].note;
  EXPECT_FALSE(short_edges[3].edge_seen);
  EXPECT_GT(short_edges[3].bound, 0.0);
  EXPECT_LT(short_edges[3].bound, box[0] - 0.05 * o.page_w);

  // No other view: nothing measured, and why.
  const auto none = render::FindCutSideEdges(seen, seen.mesh2d, box, cut, {}, {});
  EXPECT_FALSE(none[3].measured);
  EXPECT_FALSE(none[3].note.empty());
}

TEST(RenderCutSides, ThePagePastTheReferenceImageIsTexturedFromAnotherView) {
  TempDir dir;
  SceneOptions o;
  o.page_origin = {-0.6, -0.3, 1.0};
  o.radius = 0;
  SyntheticScene s = MakeScene(o);
  const SyntheticScene full = s;
  s.meshes = SeenColumns(s);
  SceneOptions far = o;
  far.page_origin = {-0.25, -0.3, 1.6};
  const SyntheticScene s2 = MakeScene(far);
  render::RenderInputs in = InputsOf(s);
  in.views = {OtherView(s, o, s2, far)};
  in.views[0].photo = dir / "view_01.png";
  WriteImageAtomic(in.views[0].photo, s2.photo);

  render::RenderOptions without;
  without.extend_cut_sides = false;
  const render::RenderResult before = render::Run(without, in);
  const render::RenderResult r = render::Run({}, in);
  Keep("cut-sides", r.rectified);
  const double px = 1 / r.pixels_per_unit;
  EXPECT_GT(before.crop_x0, 0.1 * o.page_w);
  EXPECT_NEAR(r.crop_x0, 0.0, 0.005 * o.page_w + px);  // out to the true edge
  EXPECT_NEAR(r.crop_x1, before.crop_x1, px);
  EXPECT_GT(r.other_view_fraction, 0.1);
  ASSERT_EQ(r.registrations.size(), 1u);
  // The part from the other view shows the page's texture where it belongs.
  const int x_end = int((before.crop_x0 - r.crop_x0) * r.pixels_per_unit) - 4;
  ASSERT_GT(x_end, 40);
  cv::Mat1b mask = Inner(r.page_mask, 3);
  mask.colRange(x_end, mask.cols).setTo(0);
  const SyntheticScene& truth = full;
  const cv::Mat1f a = Detail(ExpectedImage(truth, r)), b = Detail(r.rectified);
  EXPECT_GT(Correlation(a, b, mask), 0.6);
  const TileOffsets off = FindTileOffsets(a, b, mask, 32, 8);
  ASSERT_GT(off.tiles, 3);
  EXPECT_GE(off.matched, off.tiles - 1);
  EXPECT_LT(off.median, 1.5);
}

// M without its first `rows` grid rows: a top margin M stops short of.
MeshPair WithoutTopRows(const MeshPair& m, int rows) {
  MeshPair out;
  out.grid = {m.grid.nx, m.grid.ny - rows};
  for (int r = rows; r < m.grid.ny; ++r)
    for (int c = 0; c < m.grid.nx; ++c) {
      out.mesh3d.push_back(m.mesh3d[m.grid.Index(r, c)]);
      out.mesh2d.push_back(m.mesh2d[m.grid.Index(r, c)]);
    }
  return out;
}

TEST(RenderScene, RealSidePastMsBorderIsReachedAndTexturedFromTheReference) {
  SceneOptions o;
  o.radius = 0;
  const SyntheticScene full = MakeScene(o);
  ASSERT_TRUE(full.real[0]);
  SyntheticScene s = full;
  const int rows = 4;  // of 56: M stops 7 % of the page short of the top side
  s.meshes = WithoutTopRows(full.meshes, rows);
  const double top = o.page_h * rows / (full.meshes.grid.ny - 1);

  render::RenderOptions off;
  off.reach_real_sides = false;
  const render::RenderResult before = render::Run(off, InputsOf(s));
  const render::RenderResult r = render::Run({}, InputsOf(s));
  Keep("reached-side", r.rectified);
  const double px = 1 / r.pixels_per_unit;
  EXPECT_FALSE(r.sides[0].used) << "the side's samples miss M";
  EXPECT_NEAR(before.crop_y0, top, 2 * px);
  ASSERT_TRUE(r.reached_sides[0].measured);
  EXPECT_NEAR(r.crop_y0, 0.0, 0.005 * o.page_h + 2 * px);  // the true top edge
  EXPECT_NEAR(r.crop_y1, before.crop_y1, px);
  EXPECT_NEAR(r.crop_x0, before.crop_x0, px);
  EXPECT_FALSE(r.reached_sides[1].measured || r.reached_sides[2].measured ||
               r.reached_sides[3].measured);
  // The margin shows the page's texture where it belongs.
  const int y_end = int((before.crop_y0 - r.crop_y0) * r.pixels_per_unit) - 3;
  ASSERT_GT(y_end, 20);
  cv::Mat1b mask = Inner(r.page_mask, 3);
  mask.rowRange(y_end, mask.rows).setTo(0);
  ASSERT_GT(cv::countNonZero(mask), 20 * 100);
  const cv::Mat1f a = Detail(ExpectedImage(full, r)), b = Detail(r.rectified);
  EXPECT_GT(Correlation(a, b, mask), 0.6);

  // A mesh that reaches its sides is left as it was.
  const render::RenderResult whole = render::Run({}, InputsOf(full));
  for (const auto& e : whole.reached_sides) EXPECT_FALSE(e.measured);
}

// M stopping short of the top side by `left_rows` grid rows on the columns
// left of `split` and by `right_rows` right of it: the rows in between
// collapse onto the first row kept.
MeshPair WithTopRowsCollapsed(const MeshPair& m, int split, int left_rows, int right_rows) {
  MeshPair out = m;
  for (int c = 0; c < m.grid.nx; ++c) {
    const int rows = c < split ? left_rows : right_rows;
    for (int r = 0; r < rows; ++r) {
      out.mesh3d[m.grid.Index(r, c)] = m.mesh3d[m.grid.Index(rows, c)];
      out.mesh2d[m.grid.Index(r, c)] = m.mesh2d[m.grid.Index(rows, c)];
    }
  }
  return out;
}

// M gets to the top side over 40 % of it (one row short there, within
// render's snap) and misses it elsewhere; a crease M does not follow shears
// M' where it gets there, so the samples on M fit a line that tilts inside
// the page. The side is fitted (enough samples map) and reached as well,
// and the crop takes the reached edge, which lies farther out.
TEST(RenderScene, APartlyMappedSideIsReachedWhenItLiesPastItsLine) {
  SceneOptions o;
  o.radius = 0;
  o.focal = 400;  // rows of 4 px: one row short is within render's snap
  const SyntheticScene full = MakeScene(o);
  ASSERT_TRUE(full.real[0]);
  SyntheticScene s = full;
  const int split = full.meshes.grid.nx * 2 / 5;
  s.meshes = WithTopRowsCollapsed(full.meshes, split, 1, 5);
  const double row = o.page_h / (full.meshes.grid.ny - 1);
  // M' of the rows next to the left part's border sheared down towards the
  // split, as a crease M misses bends it: the samples there tilt their line.
  for (int c = 0; c < split; ++c)
    for (int r = 0; r <= 3; ++r)
      s.meshes.mesh2d[s.meshes.grid.Index(r, c)].y() +=
          0.8 * row * c / split * (3 - std::max(r, 1)) / 2.0;

  render::RenderOptions old;
  old.reach_partial_below = 0;
  const render::RenderResult before = render::Run(old, InputsOf(s));
  const render::RenderResult r = render::Run({}, InputsOf(s));
  const double px = 1 / r.pixels_per_unit;
  std::printf(
      "[render] partly mapped top: %d of %d samples on M, crop top %.4f without the "
      "reach, %.4f with it (a row is %.4f)\n",
      before.sides[0].mapped, before.sides[0].samples, before.crop_y0, r.crop_y0, row);
  ASSERT_TRUE(before.sides[0].used) << before.sides[0].note;
  EXPECT_LT(before.sides[0].mapped, 0.6 * before.sides[0].samples);
  EXPECT_GT(before.crop_y0, 0.7 * row) << "the line of the snapped samples lies inside";
  EXPECT_FALSE(r.sides[0].used);
  ASSERT_TRUE(r.reached_sides[0].measured);
  EXPECT_NEAR(r.crop_y0, 0.0, 0.005 * o.page_h + 2 * px);  // the true top edge
  EXPECT_NEAR(r.crop_y1, before.crop_y1, px);
  // A mesh that reaches its sides is left as it was.
  const render::RenderResult whole = render::Run({}, InputsOf(full));
  for (const auto& e : whole.reached_sides) EXPECT_FALSE(e.measured);
}

}  // namespace
}  // namespace docunfold::testing
