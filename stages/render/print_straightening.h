// Straightening the printed rows and columns of the rectified page in the
// image itself. M' leaves a few pixels of waviness where the points and the
// feature lines did not pin M down (a curl seen at a grazing angle, rows
// detect-features missed), and the page's similarity to a scan falls
// steeply with it. Print that runs along one direction is the evidence: the
// page is cut into narrow strips across that direction, each strip's ink
// profile is aligned to the mean profile of its window, and the smooth
// displacement that makes the profiles agree is applied. Rows first (a
// vertical displacement), then columns (a horizontal one, on the result).
#pragma once

#include <opencv2/core.hpp>

namespace docunfold::render {

struct StraightenOptions {
  bool enabled = true;
  // The analysis runs on a copy of about this many pixels (the result's
  // displacements are scaled back), so the parameters below hold at any
  // output resolution.
  double work_pixels = 600000;
  // Width of a strip and height of a window, working-copy pixels: a
  // window holds several rows of body text, a strip a few characters.
  int strip_px = 24;
  int window_px = 96;
  // Largest shift looked for (working-copy pixels): less than half a row's
  // pitch, so that a strip is not aligned one row off.
  int max_shift_px = 6;
  // A strip's shift counts only where its profile correlates with the
  // window's mean at least this well (normalised cross-correlation).
  double min_correlation = 0.5;
  // A window is looked at only where its mean profile is row-like, with at
  // least this contrast (p90 - p10) / p90: the gaps between printed rows
  // are blank, a photograph's texture is not (wood grain: 0.07-0.20; the
  // benchmark's text: 0.77-1.00).
  double min_row_contrast = 0.5;
  // The columns' pass likewise, but it needs more: a page's columns are
  // its aligned margins and rules, and the letters of different rows give
  // profiles that correlate by chance.
  double min_column_correlation = 0.8;
};

// What one direction's pass found.
struct StraightenPass {
  int strips = 0, windows = 0;
  int shifts_found = 0;     // (strip, window) cells with a confident shift
  double max_shift_px = 0;  // largest displacement applied, output pixels
};

// out(x, y) = image(map_x(x, y), map_y(x, y)).
struct Straightening {
  cv::Mat1f map_x, map_y;
  StraightenPass rows, columns;
};

// The displacement that straightens the print of `image` (8-bit, 1 or 3
// channels). A page without print, or smaller than a window, gets the
// identity. Disabled options give the identity too.
Straightening FindStraightening(const cv::Mat& image, const StraightenOptions& options);

// `image` resampled through `s` (cubic for a photo, nearest for masks and
// labels: `interpolation` is OpenCV's flag); the border pixels repeat.
cv::Mat ApplyStraightening(const cv::Mat& image, const Straightening& s, int interpolation);

}  // namespace docunfold::render
