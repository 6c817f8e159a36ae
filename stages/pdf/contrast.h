// A copy of the page for Tesseract with its print made black. Its line
// recogniser reads the grey levels as they are: pale, thin print (set07's
// receipt: the darkest tenth of its print at grey 119, its paper at 234)
// came out as "Lig" for "7.37" where the same lines stretched to black on
// white read right.
#pragma once

#include <opencv2/core.hpp>

#include "stages/pdf/unread_print.h"

namespace docunfold::pdf {

struct ContrastOptions {
  PrintThreshold print;  // what is print, as for UnreadPrint
  // Black is the grey level this percentile (0..100) of the page's pixels
  // is darker than, or the median of its print where that is darker (a page
  // with little print on it); white is the page's median, its paper.
  double black_percentile = 1;
  // A page whose black is not this many grey levels darker than its white
  // (no print) is left as it is.
  double min_range = 16;
};

// `page` (8-bit, 1 or 3 channels) in grey, stretched so that its black is 0
// and its paper 255.
cv::Mat PrintStretchedToBlack(const cv::Mat& page, const ContrastOptions& options = {});

}  // namespace docunfold::pdf
