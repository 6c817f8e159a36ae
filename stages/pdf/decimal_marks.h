// The amounts of one page share one decimal mark. Tesseract now and then
// reads a small, pale full stop as a comma ("14,66" among a receipt's
// "12.45"s), and a search for the price then misses it; where nearly all of
// a page's amounts are written with one mark, the others are given it.
#pragma once

#include <string>
#include <vector>

#include "common/json_io.h"
#include "stages/pdf/text_size.h"

namespace docunfold::pdf {

struct DecimalMarkOptions {
  // An amount is a word of one to six digits (after an optional sign and
  // currency symbol), a full stop or comma, and two digits. The page's mark
  // is the one at least min_share of its amounts have, where it has at
  // least min_amounts; with fewer, or a closer split, nothing is changed.
  int min_amounts = 5;
  double min_share = 0.8;
};

struct EvenedMarks {
  std::string mark;  // "." or ","; empty: no mark is the page's
  int amounts = 0;   // words read as an amount
  struct Evened {
    int word = 0;  // index in the reading's words
    std::string before, after;
  };
  std::vector<Evened> evened;  // the amounts given the mark
  // `prior` and the amounts given the mark, one per word, in word order.
  std::vector<WordReplacement> replacements;
};

// Gives the page's mark to the amounts of `words` (a page's reading, in its
// order, blank words included) read with the other one, after the words
// `prior` replaces (WordReplacement::word indexes `words`).
EvenedMarks EvenDecimalMarks(const std::vector<Word>& words,
                             const std::vector<WordReplacement>& prior,
                             const DecimalMarkOptions& options = {});

// pdf.json's record of `marks` (the mark null where none is the page's).
Json EvenedMarksJson(const EvenedMarks& marks);

}  // namespace docunfold::pdf
