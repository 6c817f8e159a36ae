// Edit distances between an OCR text and a reference text: character error
// rate over Unicode code points and word error rate over whitespace-split
// words.
#pragma once

#include <string>
#include <vector>

namespace docunfold::evaluate {

// Code points of a UTF-8 string; an invalid byte counts as one code point
// (U+FFFD) so that broken OCR output still yields a distance.
std::u32string Utf8ToCodePoints(const std::string& utf8);

// UTF-8 encoding of code points.
std::string CodePointsToUtf8(const std::u32string& text);

// Words separated by Unicode/ASCII whitespace.
std::vector<std::u32string> SplitWords(const std::u32string& text);

// Runs of whitespace collapsed to one space, no leading/trailing space.
std::u32string CollapseWhitespace(const std::u32string& text);

// The same on UTF-8 text: a text compared line for line with one whose
// lines and paragraphs break elsewhere (text.txt against OCR or a PDF).
std::string CollapseWhitespace(const std::string& utf8);

// Levenshtein distance (unit costs for insertion, deletion, substitution).
size_t EditDistance(const std::u32string& a, const std::u32string& b);
size_t EditDistance(const std::vector<std::u32string>& a, const std::vector<std::u32string>& b);

struct TextScores {
  size_t ed = 0;               // character edit distance
  size_t reference_chars = 0;  // code points of the reference
  size_t result_chars = 0;
  double cer = 0;  // ed / reference_chars (NaN for empty reference)
  size_t word_ed = 0;
  size_t reference_words = 0;
  double wer = 0;  // word_ed / reference_words
};

// CER over the texts as they are (OCR of result vs OCR of ground truth).
TextScores CompareTexts(const std::string& reference_utf8, const std::string& result_utf8);

// Share of the reference's words that `text` holds too, in any order,
// counted with multiplicity: what a search of the text finds. A word is
// what whitespace separates, less the punctuation at its ends (quotes, a
// full stop or comma after it), ASCII case ignored; the punctuation inside
// it counts ("14.66" is not found in "14,66", nor "11/11/2026" in
// "11/11/202"). 1 for a reference without words.
double WordsFound(const std::string& reference, const std::string& text);

}  // namespace docunfold::evaluate
