// Which way up the rectified page is. The boundary alone cannot tell a
// page's top from its bottom or sides, so the flat result is read by
// Tesseract (English) in its four quarter turns and kept the way up in
// which most words read with confidence.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <string>

namespace docunfold::render {

struct OrientationOptions {
  // Text is read at this size: the longer side of the page is scaled to
  // about this many pixels (small text needs ~20 px per line to be read).
  int read_size = 1400;
  // Only a window of this fraction of each side is read (the placement with
  // the most ink): fast, and enough words.
  double centre_fraction = 0.4;
  // A turn is applied when its readable words outnumber those of every
  // other way up by this factor and there are at least `min_words` of them.
  double margin = 1.5;
  int min_words = 4;
  // Lines of text are taken to run along the rows (or columns) when the ink
  // varies this many times more across rows than across columns (or the
  // reverse); then only two of the four turns are read.
  double line_direction_ratio = 1.4;
  // Which way the text lines run in the image when already known (from
  // optimize's lines in M'): then that, not the ink, says which two turns
  // are read.
  enum class Lines { kUnknown, kAlongRows, kAlongColumns };
  Lines lines = Lines::kUnknown;
};

struct Orientation {
  int quarter_turns = 0;       // clockwise turns applied to the image: 0..3
  std::array<int, 4> words{};  // readable words per candidate turn
  bool decided = false;        // false: too little text, left as it was
  std::string note;
};

// Reads `image` (8-bit BGR or grey) in its four quarter turns.
Orientation FindOrientation(const cv::Mat& image, const OrientationOptions& options = {});

// `image` turned clockwise by quarter_turns * 90 degrees.
cv::Mat Turn(const cv::Mat& image, int quarter_turns);

}  // namespace docunfold::render
