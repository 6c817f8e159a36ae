// pdf: the rectified page as people keep it. A PDF at the paper's size (the
// format the unfolded page's shape and print size say, else the image at a
// stated DPI) with the page image embedded once and an invisible text layer
// on the words Tesseract read; beside it ALTO XML and hOCR for archives, the
// page image the ALTO file describes, and pdf.json.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/json_io.h"
#include "common/option_table_fwd.h"
#include "stages/pdf/page_reader.h"
#include "stages/pdf/page_size.h"
#include "stages/pdf/text_size.h"

namespace docunfold::pdf {

namespace fs = std::filesystem;

enum class Enhance {
  kNone,        // the photo's colours, as render made them
  kEvenLight,   // the light's shading divided out: paper one even colour
  kBlackWhite,  // even light, then black print on white (1 bit, CCITT G4)
};

struct PdfOptions {
  std::string language = "eng";  // Tesseract's, "eng+deu" for two
  PageSizeOptions page;
  Enhance enhance = Enhance::kNone;
  int jpeg_quality = 80;  // 1..100, the embedded JPEG's quality
  // OCR reads a copy of the page with the light's shading divided out,
  // enlarged (bicubic) so that its long side has at least this many pixels
  // (an A4 page at 150 dpi); the text layer and ALTO boxes are mapped back
  // onto the page's own pixels.
  int ocr_min_long_side = 1754;
};

// Declares every option of PdfOptions.
void DeclareOptions(OptionTable& table, PdfOptions* options);

struct PdfInputs {
  fs::path render_dir;
  cv::Mat page;                  // rectified.png, 8-bit BGR
  bool shading_removed = false;  // render already divided the light out
};

// Reads rectified.png and render.json from render's output folder; throws
// InputError naming the file when either is missing or they disagree.
PdfInputs ReadPdfInputs(const fs::path& render_dir);

struct PdfResult {
  PageSize size;
  std::vector<Word> words;
  TextSize text_size;
  double mean_confidence = 0;
  size_t specks_erased = 0;  // words too small to be glyphs, painted out before the last read
  size_t pdf_bytes = 0;
  fs::path pdf_file;
  Json report;  // pdf.json
};

// Reads the page, chooses its size and writes into `out`: <name>.pdf,
// <name>.alto.xml, <name>.hocr, the page image <name>.jpg (<name>.tif for
// kBlackWhite) and pdf.json, each atomically (pdf.json last). Throws
// InputError for a missing language, OutputError when `out` is unwritable.
PdfResult Run(const PdfOptions& options, const PdfInputs& inputs, const fs::path& out,
              const std::string& name, const Json& options_record);

}  // namespace docunfold::pdf
