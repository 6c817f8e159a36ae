// Finishing Tesseract's one-page text-layer PDF with qpdf: the page set to its
// paper size with the text layer scaled onto it, the page image embedded as
// compressed (its pixels are placed by a PDF transform, never resampled), each
// word's glyphs stretched over its box, and the document's own description.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "stages/pdf/text_size.h"

namespace docunfold::pdf {

namespace fs = std::filesystem;

struct DocumentInfo {
  std::string title;
  std::string creator;   // the program that made the document
  std::string producer;  // the libraries that wrote it
};

// The page image as it goes into the PDF, already compressed.
struct PageImage {
  enum class Encoding { kJpeg, kCcittG4 };
  Encoding encoding = Encoding::kJpeg;
  std::string data;  // a JPEG (3 components) or CCITT G4 data (1 bit)
  int width = 0;
  int height = 0;
};

struct FittedPage {
  double width_pt = 0;  // the page as written
  double height_pt = 0;
  double scale_x = 1;  // how the renderer's page was stretched onto it
  double scale_y = 1;
  int words_replaced = 0;  // of the replacements given
};

// Reads the one-page PDF `in` (Tesseract's text layer), sets its page to
// width_pt x height_pt with the text stretched to fill it, each word's glyphs
// spanning its box (without the trailing space), each word of `replacements`
// showing its new text (dropped ones nothing), draws `image` under it over
// the whole page, replaces the document information and writes
// `out` (the same bytes for the same input). Throws std::runtime_error when
// qpdf cannot read or write.
FittedPage FitPage(const fs::path& in, const fs::path& out, double width_pt, double height_pt,
                   const PageImage& image, const DocumentInfo& info,
                   const std::vector<WordReplacement>& replacements = {});

// "11.3.0"
std::string QpdfVersion();

}  // namespace docunfold::pdf
