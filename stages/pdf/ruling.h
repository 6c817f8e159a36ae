// A table's ruling taken out of the copy of the page Tesseract reads. Rules
// that touch the print make its page segmentation box a table's cells as
// tall blocks of lines and glyphs (set02's statement: a quarter of its words
// found by a search); without them the cells read as words.
#pragma once

#include <opencv2/core.hpp>

#include "stages/pdf/unread_print.h"

namespace docunfold::pdf {

struct RulingOptions {
  PrintThreshold print;  // what is print, as for UnreadPrint
  // A rule runs unbroken, across or down, along at least this fraction of
  // the page's long side: a word's print, even with its letters touching, is
  // shorter.
  double min_length_of_long_side = 0.1;
  // ... and is on average at most this thick: this fraction of the page's
  // long side, or `min_thickness_px` where that is more.
  double max_thickness_of_long_side = 0.004;
  double min_thickness_px = 3;
  // Painted over with the lightest colour within this many pixels, after the
  // rules are grown by `margin_px` to take their anti-aliased edges along.
  int paper_radius_px = 3;
  int margin_px = 1;
};

struct Ruling {
  cv::Mat page;           // the page with its rules painted as paper
  double rule_share = 0;  // share (0..1) of the page's pixels painted
};

// `page` (8-bit, 1 or 3 channels) without its straight horizontal and
// vertical rules; the page itself where it has none.
Ruling WithoutRuling(const cv::Mat& page, const RulingOptions& options = {});

}  // namespace docunfold::pdf
