// The paper size of a rectified page. The unfolded page's aspect ratio names
// the format family (ISO A, Letter, Legal, a receipt roll); the size of its
// print names the member, since an A5 and an A4 page have the same shape but
// carry body text of about the same point size.
#pragma once

#include <string>
#include <vector>

namespace docunfold::pdf {

struct PaperFormat {
  std::string name;    // "a4", "letter", "receipt-80", ...
  std::string family;  // "iso", "letter", "legal", "receipt"
  double width_mm = 0;
  double height_mm = 0;         // 0: any length (a receipt roll; only its width is standard)
  bool family_default = false;  // the family's most common member
};

// ISO A3-A6, Letter, Legal, and the 80 and 58 mm receipt rolls (portrait).
const std::vector<PaperFormat>& PaperFormats();

struct PageSizeOptions {
  // "auto": the format the aspect ratio and print size say; "none": the
  // image's pixels at `dpi`; or a PaperFormats() name, taken whatever the
  // page's shape (a receipt roll keeps the page's aspect ratio).
  std::string format = "auto";
  // A page is of a family when its long/short side ratio is within this
  // fraction of the family's ratio.
  double aspect_tolerance = 0.015;
  // A page at least this many times longer than wide is a receipt.
  double receipt_min_aspect = 2.0;
  // Pixels per inch of the image when no format is matched and the text's
  // size was not measured (measured: the image at the resolution that sets
  // its body text at body_text_pt).
  double dpi = 300;
  // Typical body-text size (points) of documents and of receipts; the member
  // of a family whose size puts the page's text nearest to it is chosen.
  double body_text_pt = 10.5;
  double receipt_text_pt = 9;
  // How much nearer (natural log of the size ratio) another member must put
  // the text than the family's most common member (A4, the 80 mm roll): with
  // 0.3, a page of ISO shape is A4 unless its text would be smaller than
  // 7.6 pt or larger than 14.5 pt there.
  double other_member_margin = 0.3;
};

struct PageSize {
  std::string format = "none";  // a PaperFormats() name, or "none"
  // "aspect ratio and text size", "aspect ratio (no text read: the most common size)",
  // "given", "text size" (no format's shape), or "dpi"
  std::string rule;
  double width_mm = 0;
  double height_mm = 0;
  double page_aspect = 0;   // long / short side of the image
  double aspect_error = 0;  // relative difference from the format's ratio (0 for "none")
  double text_pt = 0;       // body-text size at this page size (0: no words measured)
  double dpi_x = 0;         // image pixels per inch across and down at this size
  double dpi_y = 0;
};

// The page size of a `width_px` x `height_px` image whose body text is set
// `text_em_px` pixels to the em (0: not measured). Throws UsageError for an
// unknown options.format.
PageSize ChoosePageSize(int width_px, int height_px, double text_em_px,
                        const PageSizeOptions& options);

constexpr double kMillimetresPerInch = 25.4;
constexpr double kPointsPerInch = 72.0;

}  // namespace docunfold::pdf
