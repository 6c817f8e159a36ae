#include "stages/pdf/markup_scale.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <regex>

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

}  // namespace docunfold::pdf
