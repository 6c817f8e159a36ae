#include "stages/evaluate/text_metrics.h"

#include <algorithm>
#include <cctype>
#include <limits>
#include <map>

namespace docunfold::evaluate {
namespace {

bool IsSpace(char32_t c) {
  return c == U' ' || c == U'\t' || c == U'\n' || c == U'\r' || c == U'\f' || c == U'\v' ||
         c == 0x85 || c == 0xA0 || c == 0x1680 || (c >= 0x2000 && c <= 0x200A) || c == 0x2028 ||
         c == 0x2029 || c == 0x202F || c == 0x205F || c == 0x3000;
}

// One row of the dynamic programme at a time: O(min(n, m)) memory.
template <typename Sequence>
size_t Levenshtein(const Sequence& a, const Sequence& b) {
  const Sequence& longer = a.size() >= b.size() ? a : b;
  const Sequence& shorter = a.size() >= b.size() ? b : a;
  std::vector<size_t> row(shorter.size() + 1);
  for (size_t j = 0; j < row.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= longer.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= shorter.size(); ++j) {
      const size_t up = row[j];
      const size_t substitute = diagonal + (longer[i - 1] == shorter[j - 1] ? 0 : 1);
      row[j] = std::min({up + 1, row[j - 1] + 1, substitute});
      diagonal = up;
    }
  }
  return row.back();
}

double Ratio(size_t num, size_t den) {
  return den == 0 ? std::numeric_limits<double>::quiet_NaN() : double(num) / double(den);
}

}  // namespace

std::u32string Utf8ToCodePoints(const std::string& utf8) {
  std::u32string out;
  out.reserve(utf8.size());
  size_t i = 0;
  while (i < utf8.size()) {
    const auto byte = static_cast<unsigned char>(utf8[i]);
    int length = byte < 0x80           ? 1
                 : (byte >> 5) == 0x6  ? 2
                 : (byte >> 4) == 0xE  ? 3
                 : (byte >> 3) == 0x1E ? 4
                                       : 0;
    char32_t code = length == 1   ? byte
                    : length == 2 ? (byte & 0x1F)
                    : length == 3 ? (byte & 0x0F)
                                  : (byte & 0x07);
    bool valid = length > 0 && i + length <= utf8.size();
    for (int k = 1; valid && k < length; ++k) {
      const auto next = static_cast<unsigned char>(utf8[i + k]);
      if ((next >> 6) != 0x2) valid = false;
      code = (code << 6) | (next & 0x3F);
    }
    if (!valid) {
      out.push_back(0xFFFD);
      ++i;
    } else {
      out.push_back(code);
      i += length;
    }
  }
  return out;
}

std::string CodePointsToUtf8(const std::u32string& text) {
  std::string out;
  out.reserve(text.size());
  for (char32_t c : text) {
    if (c < 0x80) {
      out += char(c);
    } else if (c < 0x800) {
      out += char(0xC0 | (c >> 6));
      out += char(0x80 | (c & 0x3F));
    } else if (c < 0x10000) {
      out += char(0xE0 | (c >> 12));
      out += char(0x80 | ((c >> 6) & 0x3F));
      out += char(0x80 | (c & 0x3F));
    } else {
      out += char(0xF0 | (c >> 18));
      out += char(0x80 | ((c >> 12) & 0x3F));
      out += char(0x80 | ((c >> 6) & 0x3F));
      out += char(0x80 | (c & 0x3F));
    }
  }
  return out;
}

std::vector<std::u32string> SplitWords(const std::u32string& text) {
  std::vector<std::u32string> words;
  std::u32string word;
  for (char32_t c : text) {
    if (IsSpace(c)) {
      if (!word.empty()) words.push_back(std::move(word));
      word.clear();
    } else {
      word.push_back(c);
    }
  }
  if (!word.empty()) words.push_back(std::move(word));
  return words;
}

std::u32string CollapseWhitespace(const std::u32string& text) {
  std::u32string out;
  for (const std::u32string& w : SplitWords(text)) {
    if (!out.empty()) out.push_back(U' ');
    out += w;
  }
  return out;
}

std::string CollapseWhitespace(const std::string& utf8) {
  return CodePointsToUtf8(CollapseWhitespace(Utf8ToCodePoints(utf8)));
}

size_t EditDistance(const std::u32string& a, const std::u32string& b) { return Levenshtein(a, b); }
size_t EditDistance(const std::vector<std::u32string>& a, const std::vector<std::u32string>& b) {
  return Levenshtein(a, b);
}

TextScores CompareTexts(const std::string& reference_utf8, const std::string& result_utf8) {
  const std::u32string reference = Utf8ToCodePoints(reference_utf8);
  const std::u32string result = Utf8ToCodePoints(result_utf8);
  TextScores s;
  s.ed = EditDistance(reference, result);
  s.reference_chars = reference.size();
  s.result_chars = result.size();
  s.cer = Ratio(s.ed, s.reference_chars);
  const auto reference_words = SplitWords(reference);
  s.word_ed = EditDistance(reference_words, SplitWords(result));
  s.reference_words = reference_words.size();
  s.wer = Ratio(s.word_ed, s.reference_words);
  return s;
}

namespace {

// What a search passes over at a word's ends: ASCII's punctuation, Latin-1's
// signs (« » ¡ ¿ °) and the General Punctuation block (curly quotes,
// dashes, the ellipsis).
bool IsEdgePunctuation(char32_t c) {
  if (c < 128) return !std::isalnum(int(c));
  return (c >= 0xA0 && c <= 0xBF) || c == 0xD7 || c == 0xF7 || (c >= 0x2000 && c <= 0x206F);
}

std::map<std::u32string, int> WordCounts(const std::string& text) {
  std::map<std::u32string, int> counts;
  for (const std::u32string& word : SplitWords(Utf8ToCodePoints(text))) {
    size_t from = 0, to = word.size();
    while (from < to && IsEdgePunctuation(word[from])) ++from;
    while (to > from && IsEdgePunctuation(word[to - 1])) --to;
    if (from == to) continue;
    std::u32string core = word.substr(from, to - from);
    for (char32_t& c : core)
      if (c < 128) c = char32_t(std::tolower(int(c)));
    ++counts[core];
  }
  return counts;
}

}  // namespace

double WordsFound(const std::string& reference, const std::string& text) {
  const std::map<std::u32string, int> wanted = WordCounts(reference), found = WordCounts(text);
  int total = 0, matched = 0;
  for (const auto& [word, n] : wanted) {
    total += n;
    const auto it = found.find(word);
    if (it != found.end()) matched += std::min(n, it->second);
  }
  return total ? double(matched) / total : 1;
}

}  // namespace docunfold::evaluate
