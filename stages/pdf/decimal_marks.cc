#include "stages/pdf/decimal_marks.h"

#include <algorithm>
#include <map>
#include <regex>

#include "stages/pdf/word_reread.h"

namespace docunfold::pdf {

EvenedMarks EvenDecimalMarks(const std::vector<Word>& words,
                             const std::vector<WordReplacement>& prior,
                             const DecimalMarkOptions& o) {
  // Sign and currency, the mark, the two digits after it.
  static const std::regex kAmount(R"(^([-+]?(?:\$|£|€)?[0-9]{1,6})([.,])([0-9]{2})$)");
  std::vector<std::string> text(words.size());
  for (size_t i = 0; i < words.size(); ++i) text[i] = words[i].text;
  std::map<int, WordReplacement> by_word;
  for (const WordReplacement& r : prior) {
    by_word[r.word] = r;
    if (r.word >= 0 && r.word < int(text.size())) text[r.word] = r.text;
  }
  std::vector<std::pair<int, std::smatch>> amounts;
  int full_stops = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    std::smatch m;
    if (!std::regex_match(text[i], m, kAmount)) continue;
    full_stops += m[2] == ".";
    amounts.emplace_back(int(i), m);
  }
  EvenedMarks e;
  e.amounts = int(amounts.size());
  const int commas = e.amounts - full_stops;
  if (e.amounts >= o.min_amounts && std::max(full_stops, commas) >= o.min_share * e.amounts)
    e.mark = full_stops >= commas ? "." : ",";
  if (!e.mark.empty()) {
    const std::vector<int> in_files = NumbersInFiles(words);
    for (const auto& [i, m] : amounts) {
      if (m[2] == e.mark) continue;
      const std::string evened = m[1].str() + e.mark + m[3].str();
      e.evened.push_back({i, text[i], evened});
      const auto [it, fresh] = by_word.try_emplace(i);
      WordReplacement& r = it->second;
      if (fresh) {
        r.word = i;
        r.in_files = in_files[i];
        r.old_text = words[i].text;
        r.confidence = words[i].confidence;
        r.box = words[i].box;
      }
      r.text = evened;
    }
  }
  for (auto& [i, r] : by_word) e.replacements.push_back(r);
  return e;
}

Json EvenedMarksJson(const EvenedMarks& marks) {
  Json evened = Json::array();
  for (const EvenedMarks::Evened& e : marks.evened) evened.push_back({e.word, e.before, e.after});
  return {{"mark", marks.mark.empty() ? Json() : Json(marks.mark)},
          {"amounts", marks.amounts},
          {"evened", evened}};
}

}  // namespace docunfold::pdf
