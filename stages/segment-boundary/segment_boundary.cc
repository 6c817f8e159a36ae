#include "stages/segment-boundary/segment_boundary.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "common/errors.h"
#include "common/option_table.h"
#include "common/program.h"
#include "stages/segment-boundary/boundary_internal.h"
#include "stages/segment-boundary/text_orientation.h"

namespace docunfold::boundary {

void DeclareOptions(OptionTable& table, BoundaryOptions* o, OtherViews* views) {
  table.Value("work-size", &o->work_size, 64, 8192,
              "long side (px) of the downscaled image the page is found on");
  table.Value("frame-fraction", &o->frame_fraction, 0.005, 0.3,
              "width of the image frame that teaches the background colour, as a fraction of "
              "the short side");
  table.Value("table-distance", &o->table_distance, 1.0, 100.0,
              "colour distance (std. deviations of the background) beyond which a pixel is not "
              "background");
  table.Value("weak-table-distance", &o->weak_table_distance, 1.0, 100.0,
              "colour distance (std. deviations of the background) from which pixels are page "
              "where they touch it in areas --weak-min-width wide (e.g. the shaded panel of a "
              "fold); set it to --table-distance to turn off");
  table.Value("weak-min-width", &o->weak_min_width, 1, 101,
              "smallest width (px of the downscaled image) of such an area");
  table.Value("min-area", &o->min_area_fraction, 0.0, 1.0,
              "smallest page area, as a fraction of the image");
  table.Value("border-tolerance", &o->border_tolerance_px, 0.0, 50.0,
              "outline within this many pixels of the image border is cut off");
  table.Value("max-cut-fraction", &o->max_cut_fraction, 0.0, 1.0,
              "a side with more of its length on the image border is not real");
  table.Value("contour-epsilon", &o->contour_epsilon_px, 0.0, 20.0,
              "Douglas-Peucker tolerance (px) of the stored outline and sides");
  table.Choice("orientation", &o->orientation,
               {{"auto", OrientationSource::kAuto},
                {"text", OrientationSource::kText},
                {"geometry", OrientationSource::kGeometry}},
               "which side is the top: auto (text if it tells, else geometry), text, geometry");
  table.Switch("verbose", &o->verbose, "log each step and its time");
  CLI::Option* views_dir = table.Path(
      "views", &views->views_dir,
      "folder of the photos (e.g. <data>/images): also find the page in every other view "
      "that --cameras registers, into <out>/views/<photo name>/ (render looks there past "
      "the border of a reference image that cuts the page off)");
  CLI::Option* cameras =
      table.Path("cameras", &views->cameras_path, "sfm's cameras.json (with --views)");
  views_dir->needs(cameras);
  cameras->needs(views_dir);
}

namespace {

// Which side of the page is the top (an index into `corners`, clockwise in
// the image), from the text or the geometry as `source` says; records how in
// `orientation`. Throws InputError when the text must tell and does not.
int ChooseTopSide(const cv::Mat3b& full, const cv::Mat1b& mask,
                  const std::array<cv::Point2d, 4>& corners, OrientationSource source,
                  Orientation* orientation) {
  int top = detail::GeometricTopSide(corners);
  orientation->method = "geometry";
  if (source != OrientationSource::kGeometry) {
    TextOrientation text = EstimateTextTopSide(full, mask, corners);
    orientation->confidence = text.confidence;
    orientation->votes = text.votes;
    if (text.top_side >= 0) {
      top = text.top_side;
      orientation->method = "text";
    } else if (source == OrientationSource::kText) {
      throw InputError("cannot tell the page's orientation from its text: " + text.why);
    }
  }
  return top;
}

}  // namespace

BoundaryResult SegmentBoundary(const cv::Mat& image, const BoundaryOptions& options) {
  if (image.empty() || image.type() != CV_8UC3) throw InputError("expected an 8-bit colour image");
  if (image.cols < 16 || image.rows < 16)
    throw InputError("image too small (" + std::to_string(image.cols) + "x" +
                     std::to_string(image.rows) + ")");
  const cv::Mat3b full = image;
  const auto start = std::chrono::steady_clock::now();
  const internal::StepLog step = [&](const std::string& what) {
    if (options.verbose) Log(what + " (" + Fixed(SecondsSince(start), 3) + " s)");
  };

  // 1. Page region on a downscaled image: everything that is not table.
  const internal::CoarseRegion region = internal::FindCoarseRegion(full, options, step);
  step("coarse region");
  // 2. Outline at full resolution.
  const cv::Mat1b mask = internal::RefinePageMask(full, region);
  step("outline refined at full resolution");
  BoundaryResult result;
  result.mask = mask;
  result.area_fraction = cv::countNonZero(mask) / (double(mask.cols) * mask.rows);
  const std::vector<cv::Point> contour = internal::ClockwiseOutline(mask);
  result.contour =
      internal::Simplify(internal::ToDouble(contour), options.contour_epsilon_px, true);

  // 3. Corners: clockwise, then rotated so that the top side is first.
  const internal::BorderTest on_border =
      internal::OnImageBorder(mask.size(), options.border_tolerance_px);
  const internal::ShadingImage shading = internal::MakeShadingImage(region.small, mask, full.cols);
  std::array<int, 4> idx = internal::FindCorners(contour, shading, on_border);
  std::array<cv::Point2d, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = contour[idx[i]];
  step("corners");
  const int top = ChooseTopSide(full, mask, corners, options.orientation, &result.orientation);
  step("orientation by " + result.orientation.method);
  std::rotate(idx.begin(), idx.begin() + top, idx.end());
  for (int i = 0; i < 4; ++i) {
    const cv::Point2d c =
        detail::RefineCorner(contour, idx[i], internal::CornerReach(contour.size()));
    result.corners[i] = {std::clamp(c.x, 0.0, mask.cols - 1.0),
                         std::clamp(c.y, 0.0, mask.rows - 1.0)};
  }

  // 4. Sides along the outline, and which parts of them lie on the image border.
  for (int i = 0; i < 4; ++i) result.corner_in_image[i] = !on_border(contour[idx[i]]);
  for (int i = 0; i < 4; ++i)
    result.sides[i] = internal::TraceSide(contour, idx, i, result.corners, on_border, options);
  // 5. Corners folded over or under the page, completed past the fold.
  result.folded_corners = internal::CompleteFoldedCorners(contour, shading, on_border,
                                                          options.contour_epsilon_px, &result);
  return result;
}

}  // namespace docunfold::boundary
