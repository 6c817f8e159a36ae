#include "stages/pdf/page_size.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/errors.h"

namespace docunfold::pdf {
namespace {

constexpr double kMillimetresPerPoint = kMillimetresPerInch / kPointsPerInch;

// `size` with its width and height set from `format` for a page of the given
// shape (a receipt roll: the page's own length at the roll's width).
void SetFormat(const PaperFormat& format, double aspect, bool landscape, PageSize* size) {
  size->format = format.name;
  double w = format.width_mm;
  double h = format.height_mm > 0 ? format.height_mm : format.width_mm * aspect;
  if (landscape) std::swap(w, h);
  size->width_mm = w;
  size->height_mm = h;
  size->aspect_error =
      format.height_mm > 0 ? std::abs(aspect / (format.height_mm / format.width_mm) - 1) : 0.0;
}

// Body-text size (points) of a page printed on `format`.
double TextPoints(const PaperFormat& format, double text_em_px, int short_px, int long_px) {
  const double px_per_mm =
      format.height_mm > 0 ? long_px / format.height_mm : short_px / format.width_mm;
  return text_em_px / px_per_mm / kMillimetresPerPoint;
}

}  // namespace

const std::vector<PaperFormat>& PaperFormats() {
  static const std::vector<PaperFormat> formats = {
      {"a3", "iso", 297, 420, false},           {"a4", "iso", 210, 297, true},
      {"a5", "iso", 148, 210, false},           {"a6", "iso", 105, 148, false},
      {"letter", "letter", 215.9, 279.4, true}, {"legal", "legal", 215.9, 355.6, true},
      {"receipt-80", "receipt", 80, 0, true},   {"receipt-58", "receipt", 58, 0, false},
  };
  return formats;
}

PageSize ChoosePageSize(int width_px, int height_px, double text_em_px, const PageSizeOptions& o) {
  const int long_px = std::max(width_px, height_px);
  const int short_px = std::max(1, std::min(width_px, height_px));
  const bool landscape = width_px > height_px;
  PageSize size;
  size.page_aspect = double(long_px) / short_px;
  auto finish = [&]() {
    size.dpi_x = width_px / (size.width_mm / kMillimetresPerInch);
    size.dpi_y = height_px / (size.height_mm / kMillimetresPerInch);
    return size;
  };
  auto by_dpi = [&]() {
    size.format = "none";
    size.rule = "dpi";
    size.width_mm = width_px / o.dpi * kMillimetresPerInch;
    size.height_mm = height_px / o.dpi * kMillimetresPerInch;
    return finish();
  };

  if (o.format == "none") return by_dpi();
  if (o.format != "auto") {
    const auto& all = PaperFormats();
    auto it = std::find_if(all.begin(), all.end(),
                           [&](const PaperFormat& f) { return f.name == o.format; });
    if (it == all.end()) throw UsageError("unknown paper format '" + o.format + "'");
    SetFormat(*it, size.page_aspect, landscape, &size);
    size.rule = "given";
    return finish();
  }

  // The members whose shape the page has.
  const bool receipt = size.page_aspect >= o.receipt_min_aspect;
  std::vector<const PaperFormat*> candidates;
  for (const PaperFormat& f : PaperFormats()) {
    if (receipt != (f.family == "receipt")) continue;
    if (f.height_mm > 0 &&
        std::abs(size.page_aspect / (f.height_mm / f.width_mm) - 1) > o.aspect_tolerance)
      continue;
    candidates.push_back(&f);
  }
  // No format's shape (a page cut off, an odd card): the print's size is the
  // one measure of the page's left.
  if (candidates.empty() && text_em_px > 0) {
    const double dpi = text_em_px / (o.body_text_pt / kPointsPerInch);
    size.format = "none";
    size.rule = "text size";
    size.text_pt = o.body_text_pt;
    size.width_mm = width_px / dpi * kMillimetresPerInch;
    size.height_mm = height_px / dpi * kMillimetresPerInch;
    return finish();
  }
  if (candidates.empty()) return by_dpi();

  const PaperFormat* chosen = nullptr;
  if (text_em_px > 0) {
    const double typical = receipt ? o.receipt_text_pt : o.body_text_pt;
    double best = std::numeric_limits<double>::infinity();
    for (const PaperFormat* f : candidates) {
      const double pt = TextPoints(*f, text_em_px, short_px, long_px);
      const double cost =
          std::abs(std::log(pt / typical)) + (f->family_default ? 0.0 : o.other_member_margin);
      if (cost < best) best = cost, chosen = f, size.text_pt = pt;
    }
    size.rule = "aspect ratio and text size";
  } else {
    chosen = candidates.front();
    for (const PaperFormat* f : candidates)
      if (f->family_default) chosen = f;
    size.rule = "aspect ratio (no text read: the most common size)";
  }
  SetFormat(*chosen, size.page_aspect, landscape, &size);
  return finish();
}

}  // namespace docunfold::pdf
