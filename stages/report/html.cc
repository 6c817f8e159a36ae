#include "stages/report/html.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace docunfold::report {

std::string Base64(const std::vector<unsigned char>& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const unsigned v = (unsigned(bytes[i]) << 16) |
                       (i + 1 < bytes.size() ? unsigned(bytes[i + 1]) << 8 : 0) |
                       (i + 2 < bytes.size() ? unsigned(bytes[i + 2]) : 0);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[v & 63] : '=';
  }
  return out;
}

std::string InlineImage(const cv::Mat& image, int max_width, const std::string& alt, bool png) {
  cv::Mat scaled = image;
  if (image.cols > max_width)
    cv::resize(image, scaled, cv::Size(max_width, std::max(1, image.rows * max_width / image.cols)),
               0, 0, cv::INTER_AREA);
  std::vector<unsigned char> bytes;
  cv::imencode(png ? ".png" : ".jpg", scaled, bytes,
               png ? std::vector<int>{} : std::vector<int>{cv::IMWRITE_JPEG_QUALITY, 88});
  return "<img src=\"data:image/" + std::string(png ? "png" : "jpeg") + ";base64," + Base64(bytes) +
         "\" width=\"" + std::to_string(scaled.cols) + "\" height=\"" +
         std::to_string(scaled.rows) + "\" alt=\"" + MarkupEscape(alt) + "\">";
}

namespace {

const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                          "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};

std::string Num(double v) {
  char buf[32];
  if (v != 0 && (std::abs(v) < 1e-2 || std::abs(v) >= 1e4))
    std::snprintf(buf, sizeof buf, "%.0e", v);
  else
    std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// Round-number ticks covering [lo, hi].
std::vector<double> Ticks(double lo, double hi, int wanted) {
  const double span = std::max(hi - lo, 1e-12);
  const double raw = span / wanted;
  const double mag = std::pow(10, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * mag) {
      step = m * mag;
      break;
    }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * span; t += step)
    ticks.push_back(std::abs(t) < 1e-12 * span ? 0 : t);
  return ticks;
}

}  // namespace

std::string SvgScatter(const std::vector<PlotPoint>& points, const PlotOptions& o) {
  const int left = 64, right = 16, top = 12, bottom = 44;
  const int w = o.width - left - right, h = o.height - top - bottom;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  bool first = true;
  for (const PlotPoint& p : points) {
    const double y = o.log_y ? std::log10(std::max(p.y, 1e-300)) : p.y;
    if (!std::isfinite(y) || !std::isfinite(p.x)) continue;
    if (first) {
      x0 = x1 = p.x;
      y0 = y1 = y;
      first = false;
    }
    x0 = std::min(x0, p.x);
    x1 = std::max(x1, p.x);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  }
  if (x1 - x0 < 1e-9) x1 = x0 + 1;
  if (y1 - y0 < 1e-9) {
    y0 -= 0.5;
    y1 += 0.5;
  }
  const double pad = 0.05 * (y1 - y0);
  y0 -= pad;
  y1 += pad;
  auto X = [&](double x) { return left + (x - x0) / (x1 - x0) * w; };
  auto Y = [&](double y) { return top + (1 - (y - y0) / (y1 - y0)) * h; };
  std::string s = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(o.width) +
                  "\" height=\"" + std::to_string(o.height) +
                  "\" font-family=\"sans-serif\" font-size=\"11\">";
  s += "<rect x=\"" + std::to_string(left) + "\" y=\"" + std::to_string(top) + "\" width=\"" +
       std::to_string(w) + "\" height=\"" + std::to_string(h) +
       "\" fill=\"none\" stroke=\"#888\"/>";
  char buf[256];
  for (double t : Ticks(x0, x1, 6)) {
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#ddd\"/>"
                  "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%s</text>",
                  X(t), top, X(t), top + h, X(t), top + h + 14, Num(t).c_str());
    s += buf;
  }
  // On a log axis, ticks at whole powers of ten when the range allows.
  std::vector<double> y_ticks = Ticks(y0, y1, 5);
  if (o.log_y && y1 - y0 >= 1) {
    y_ticks.clear();
    for (double t = std::ceil(y0); t <= y1; t += 1) y_ticks.push_back(t);
  }
  for (double t : y_ticks) {
    const std::string label = Num(o.log_y ? std::pow(10.0, t) : t);
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%d\" y1=\"%.1f\" x2=\"%d\" y2=\"%.1f\" stroke=\"#ddd\"/>"
                  "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%s</text>",
                  left, Y(t), left + w, Y(t), left - 4, Y(t) + 4, MarkupEscape(label).c_str());
    s += buf;
  }
  std::snprintf(buf, sizeof buf, "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">%s</text>",
                left + w / 2, o.height - 8, MarkupEscape(o.x_label).c_str());
  s += buf;
  std::snprintf(buf, sizeof buf,
                "<text x=\"12\" y=\"%d\" text-anchor=\"middle\" transform=\"rotate(-90 12 %d)\">"
                "%s</text>",
                top + h / 2, top + h / 2, MarkupEscape(o.y_label).c_str());
  s += buf;
  for (const PlotPoint& p : points) {
    const double y = o.log_y ? std::log10(std::max(p.y, 1e-300)) : p.y;
    if (!std::isfinite(y) || !std::isfinite(p.x)) continue;
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"%s\"/>", X(p.x),
                  Y(y), kColours[p.series % 8]);
    s += buf;
  }
  for (size_t i = 0; i < o.series_names.size(); ++i) {
    std::snprintf(buf, sizeof buf,
                  "<circle cx=\"%d\" cy=\"%d\" r=\"4\" fill=\"%s\"/>"
                  "<text x=\"%d\" y=\"%d\">%s</text>",
                  left + w - 90, top + 12 + int(i) * 15, kColours[i % 8], left + w - 82,
                  top + 16 + int(i) * 15, MarkupEscape(o.series_names[i]).c_str());
    s += buf;
  }
  return s + "</svg>";
}

}  // namespace docunfold::report
