// Words Tesseract doubted, read again on their own. Its line recogniser reads
// the grey levels as they are: pale, thin print (a receipt's prices) comes
// out as other characters, read with little confidence, where the same words
// cut out, made black on white and read as one line come out right and sure.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/json_io.h"
#include "stages/pdf/text_size.h"

namespace docunfold::pdf {

struct RereadOptions {
  // A word read with a confidence (0..1) below this is doubted; doubted
  // words next to each other on one of Tesseract's lines, less than
  // max_gap_heights word heights apart, are read again together (Tesseract
  // often cuts one doubted word into two or three).
  double max_confidence = 0.8;
  double max_gap_heights = 2.0;
  // The group's box, grown by margin_heights of its height on every side,
  // is cut out and scaled to a word height of height_px pixels.
  double margin_heights = 0.25;
  int height_px = 48;
  // The new reading replaces the group's where its mean confidence is at
  // least min_confidence and at least min_gain above the group's, every word
  // of it has a letter or digit, and every one made of letters alone is in
  // the language's dictionary (a misread word that Tesseract is sure of is
  // most often not a word, or a lone symbol where a letter was).
  double min_confidence = 0.85;
  double min_gain = 0.3;
};

// Whether `text` is only whitespace: Tesseract reads such words, and its
// renderers leave them out.
bool IsBlank(const std::string& text);

// Each word's number among the non-blank words of `words`, as Tesseract's
// files number them (-1: blank).
std::vector<int> NumbersInFiles(const std::vector<Word>& words);

// The doubted words of `words` (in reading order, blank ones never), grouped
// as above.
std::vector<std::vector<int>> DoubtedWordGroups(const std::vector<Word>& words,
                                                const RereadOptions& options = {});

struct Rereading {
  std::vector<WordReplacement> replacements;  // in word order
  int groups = 0;                             // groups read again
  int groups_replaced = 0;
};

// Reads every group of doubted words of `words` again from `image` (the
// copy they were read from, their boxes in its pixels) as one line in
// Otsu's black and white, by Tesseract in `language`, and says which to
// replace: the group's first words take the new words in order, the last
// of them the rest of the new reading; words left over are dropped.
Rereading RereadDoubtedWords(const cv::Mat& image, const std::vector<Word>& words,
                             const std::string& language, const RereadOptions& options = {});

// pdf.json's record of `rereading`: its counts and [word, old text, new
// text] of each word replaced ("" dropped).
Json RereadingJson(const Rereading& rereading, bool in_every_file);

// `words` with `replacements` made (dropped words left out).
std::vector<Word> WithReplacements(const std::vector<Word>& words,
                                   const std::vector<WordReplacement>& replacements);

}  // namespace docunfold::pdf
