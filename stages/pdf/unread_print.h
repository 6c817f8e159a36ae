// How much of a page's print no word read covers. Tesseract's automatic page
// segmentation now and then leaves a whole column or block unread (set07's
// column of prices on a receipt): the print is there, the words are not.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "stages/pdf/text_size.h"

namespace docunfold::pdf {

// Print: pixels at least `contrast` grey levels darker than the mean of a
// `window_px` square around them (the light's shading does not matter).
struct PrintThreshold {
  int window_px = 31;
  double contrast = 15;
};

// `page` (8-bit, 1 or 3 channels) in grey: a grey page is itself.
cv::Mat Grey(const cv::Mat& page);

// `page`'s print (8-bit, 255 where print).
cv::Mat PrintPixels(const cv::Mat& page, const PrintThreshold& threshold = {});

struct UnreadPrintOptions {
  PrintThreshold print;
  // Only glyph-sized marks count: connected components smaller than these
  // fractions of the page's height and width (a table's frame or a rule is
  // not print to read), of at least `min_area_px` pixels (not noise).
  double max_height_of_page = 0.05;
  double max_width_of_page = 0.2;
  int min_area_px = 4;
  // A word's box grown by this many pixels covers the print along its edge.
  int margin_px = 2;
  // The page's border (this fraction of its short side) is left out: the
  // crop's edge and whatever lies beyond the page there.
  double border_of_short_side = 0.02;
};

// The share (0..1) of `page`'s print pixels outside every word's box (`words`
// in `page`'s pixels; words of whitespace only cover nothing). 0 for a page
// without print.
double UnreadPrint(const cv::Mat& page, const std::vector<Word>& words,
                   const UnreadPrintOptions& options = {});

}  // namespace docunfold::pdf
