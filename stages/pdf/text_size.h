// How large the page's body text is, in pixels to the em, from what
// Tesseract read: the height of confidently read words, leaving out those
// it boxed taller than their lines are apart (it does so with small print,
// and with a paragraph here and there of a larger one); where too few are
// left, the distance between lines.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace docunfold::pdf {

struct Word {
  cv::Rect box;           // image pixels
  double confidence = 0;  // 0..1
  std::string text;       // UTF-8
  int line = -1;          // index of the TextLine it was read in (-1: none known)
};

// The words' mean confidence (0 for none).
double MeanConfidence(const std::vector<Word>& words);

// A word of a page's reading given another text after it was read: where
// Tesseract's files show `old_text`, they are to show `text` over `box`
// (image pixels). Empty text: the word is dropped, its print now part of the
// word before.
struct WordReplacement {
  int word = 0;      // index in the reading's words
  int in_files = 0;  // its number in Tesseract's files, which leave out blank words
  std::string old_text;
  std::string text;
  double confidence = 0;  // 0..1
  cv::Rect box;
  // The word's glyphs, which start where Tesseract put them, span this many
  // times the old word's width (the new box's right edge from the old left).
  double width_ratio = 1;
};

struct TextLine {
  int block = 0;  // Tesseract's block, counted from 0
  cv::Rect box;   // image pixels
  cv::Point2d baseline_start, baseline_end;
};

struct TextSizeOptions {
  // Body words: two or more characters with a lower-case letter, read with
  // at least this confidence; fewer than min_words of them and the text's
  // size is not measured.
  double min_confidence = 0.8;
  size_t min_words = 20;
  // Median body-word box height and distance between a paragraph's
  // baselines, as multiples of the font size.
  double word_height_em = 0.75;
  double line_pitch_em = 1.35;
  // A word boxed this close to its line's pitch (the distance to the nearer
  // neighbouring line of its block; the page's median pitch for a word of
  // no known line) or taller spans more than a line: its height is not the
  // text's. Too few words left and the text's size is the line pitch's; so
  // it is where the pitch gives a smaller size than the word height.
  double max_word_height_of_pitch = 0.9;
  size_t min_line_pairs = 5;
};

struct TextSize {
  double em_px = 0;  // 0: not measured
  // "word height", "line pitch", "line pitch (below the word height's)" or
  // why not measured.
  std::string cue;
  size_t words = 0;           // body words
  double word_height_px = 0;  // median over the body words within their line (0: none)
  double line_pitch_px = 0;   // median over neighbouring lines of a block (0: too few)
};

TextSize EstimateTextSize(const std::vector<Word>& words, const std::vector<TextLine>& lines,
                          const TextSizeOptions& options = {});

// The boxes of the words that fit in a square `side_px` across: specks of
// dirt or noise Tesseract read as a character ('-', 'g' a pixel or two
// across on bare paper), not glyphs. None when `side_px` is 0.
std::vector<cv::Rect> SpeckBoxes(const std::vector<Word>& words, double side_px);

}  // namespace docunfold::pdf
