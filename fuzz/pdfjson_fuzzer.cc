// pdf's pdf.json as the report reads it back: the PDF's summary line and its
// words drawn over the page image (a small page).
#include <cstddef>
#include <cstdint>
#include <exception>

#include "common/json_io.h"
#include "fuzz/fuzz_input.h"
#include "stages/report/stage_outputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using docunfold::Json;
  static const cv::Mat page(48, 64, CV_8UC3, cv::Scalar(250, 250, 250));
  Json doc;  // the report's TryJson: null when the file does not parse
  try {
    doc = docunfold::ReadJsonFile(docunfold::fuzz::WriteInput(data, size, "pdf.json"));
  } catch (const std::exception&) {
    return 0;
  }
  try {
    docunfold::report::PdfSummary(doc);
    docunfold::report::PdfWordsSvg(page, doc, 32);
  } catch (const std::exception&) {
    // A clean rejection of a bad file is what the reader should do.
  }
  return 0;
}
