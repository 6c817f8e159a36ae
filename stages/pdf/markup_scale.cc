#include "stages/pdf/markup_scale.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <regex>

#include "common/markup.h"

namespace docunfold::pdf {
namespace {

// `text` with each match of `pattern` replaced by `replace(match)`.
std::string ReplaceMatches(const std::string& text, const std::regex& pattern,
                           const std::function<std::string(const std::smatch&)>& replace) {
  std::string out;
  auto last = text.cbegin();
  for (std::sregex_iterator it(text.begin(), text.end(), pattern), end; it != end; ++it) {
    out.append(last, (*it)[0].first);
    out += replace(*it);
    last = (*it)[0].second;
  }
  out.append(last, text.cend());
  return out;
}

// Positions round down and extents up, so that a box mapped onto fewer
// pixels still covers what it boxed (a 1-pixel mark read at 3x is not lost).
std::string Floor(double v) { return std::to_string(long(std::floor(v + 1e-9))); }
std::string Ceil(double v) { return std::to_string(long(std::ceil(v - 1e-9))); }

std::string Decimal(double v, int decimals) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

std::string ScaleAltoPixels(const std::string& alto, double scale) {
  if (scale == 1) return alto;
  static const std::regex attribute(R"re(\b(HPOS|VPOS|WIDTH|HEIGHT)="(-?[0-9]+(?:\.[0-9]+)?)")re");
  return ReplaceMatches(alto, attribute, [scale](const std::smatch& m) {
    const std::string key = m[1].str();
    const double v = std::stod(m[2].str()) * scale;
    return key + "=\"" + (key == "WIDTH" || key == "HEIGHT" ? Ceil(v) : Floor(v)) + "\"";
  });
}

std::string ScaleHocrPixels(const std::string& hocr, double scale, int read_dpi, int page_dpi) {
  static const std::regex bbox(R"re(\bbbox (-?[0-9]+) (-?[0-9]+) (-?[0-9]+) (-?[0-9]+))re");
  static const std::regex baseline(R"re(\bbaseline (-?[0-9.]+) (-?[0-9.]+))re");
  static const std::regex size(R"re(\b(x_size|x_descenders|x_ascenders) (-?[0-9.]+))re");
  static const std::regex resolution(R"re(\bscan_res [0-9]+ [0-9]+)re");
  std::string out = hocr;
  if (scale != 1) {
    out = ReplaceMatches(out, bbox, [scale](const std::smatch& m) {
      return "bbox " + Floor(std::stod(m[1]) * scale) + " " + Floor(std::stod(m[2]) * scale) + " " +
             Ceil(std::stod(m[3]) * scale) + " " + Ceil(std::stod(m[4]) * scale);
    });
    out = ReplaceMatches(out, baseline, [scale](const std::smatch& m) {
      return "baseline " + m[1].str() + " " + std::to_string(std::lround(std::stod(m[2]) * scale));
    });
    out = ReplaceMatches(out, size, [scale](const std::smatch& m) {
      return m[1].str() + " " + Decimal(std::stod(m[2]) * scale, 4);
    });
  }
  if (read_dpi != page_dpi) {
    const std::string res = "scan_res " + std::to_string(page_dpi) + " " + std::to_string(page_dpi);
    out = ReplaceMatches(out, resolution, [&res](const std::smatch&) { return res; });
  }
  return out;
}

namespace {

// The words of `markup` that `element` matches, in order, each given by
// `edit(match, replacement)` where one of `replacements` numbers it
// (WordReplacement::in_files; its old text checked by `text_of(match)`);
// nullopt where one does not match.
std::optional<std::string> EditWords(
    const std::string& markup, const std::regex& element,
    const std::function<std::string(const std::smatch&)>& text_of,
    const std::vector<WordReplacement>& replacements,
    const std::function<std::string(const std::smatch&, const WordReplacement&)>& edit) {
  std::map<int, const WordReplacement*> by_word;
  for (const WordReplacement& r : replacements) by_word[r.in_files] = &r;
  if (by_word.empty()) return markup;
  int word = 0;
  bool aligned = true;
  std::string out = ReplaceMatches(markup, element, [&](const std::smatch& m) {
    const auto it = by_word.find(word++);
    if (it == by_word.end()) return m[0].str();
    if (text_of(m) != MarkupEscape(it->second->old_text)) aligned = false;
    return edit(m, *it->second);
  });
  if (!aligned || word <= by_word.rbegin()->first) return std::nullopt;
  return out;
}

}  // namespace

std::optional<std::string> ReplaceAltoWords(const std::string& alto,
                                            const std::vector<WordReplacement>& replacements) {
  static const std::regex string_element(
      R"re((<SP\b[^>]*/>\s*)?<String ID="([^"]*)"[^>]*CONTENT="([^"]*)"[^>]*/>)re");
  return EditWords(
      alto, string_element, [](const std::smatch& m) { return m[3].str(); }, replacements,
      [](const std::smatch& m, const WordReplacement& r) -> std::string {
        if (r.text.empty()) return "";
        const cv::Rect& b = r.box;
        return m[1].str() + "<String ID=\"" + m[2].str() + "\" HPOS=\"" + std::to_string(b.x) +
               "\" VPOS=\"" + std::to_string(b.y) + "\" WIDTH=\"" + std::to_string(b.width) +
               "\" HEIGHT=\"" + std::to_string(b.height) + "\" WC=\"" + Decimal(r.confidence, 2) +
               "\" CONTENT=\"" + MarkupEscape(r.text) + "\"/>";
      });
}

std::optional<std::string> ReplaceHocrWords(const std::string& hocr,
                                            const std::vector<WordReplacement>& replacements) {
  static const std::regex word_span(
      R"re((\s*)<span class='ocrx_word' id='([^']*)' title='bbox [-0-9 ]+;([^']*)'>(.*?)</span>)re");
  static const std::regex confidence(R"re(x_wconf [0-9]+)re");
  return EditWords(
      hocr, word_span, [](const std::smatch& m) { return m[4].str(); }, replacements,
      [](const std::smatch& m, const WordReplacement& r) -> std::string {
        if (r.text.empty()) return "";
        const cv::Rect& b = r.box;
        const std::string properties = std::regex_replace(
            m[3].str(), confidence, "x_wconf " + std::to_string(std::lround(100 * r.confidence)));
        return m[1].str() + "<span class='ocrx_word' id='" + m[2].str() + "' title='bbox " +
               std::to_string(b.x) + " " + std::to_string(b.y) + " " + std::to_string(b.br().x) +
               " " + std::to_string(b.br().y) + ";" + properties + "'>" + MarkupEscape(r.text) +
               "</span>";
      });
}

}  // namespace docunfold::pdf
