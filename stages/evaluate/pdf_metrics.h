// The searchable PDF against the data set's truth: how well its text layer
// serves a search and a copy (poppler's pdftotext, as a viewer extracts it)
// and whether its page has the paper's true size. What a user keeps is the
// PDF, so this measures the pdf stage's output itself, not the image.
#pragma once

#include <filesystem>
#include <string>

#include "common/json_io.h"

namespace docunfold::evaluate {

namespace fs = std::filesystem;

// True when `data` has ground_truth/text.txt (a PDF is measured against it).
bool HasTrueText(const fs::path& data);

struct PdfMetricsResult {
  double words_found = 0;
  // CER of pdftotext's text in its reading order (what a viewer's select-all
  // and copy give), whitespace collapsed.
  double cer_reading_order = 0;
  double size_error = 0;  // largest relative error of page 1's sides (NaN: no page.json)
  Json document;          // the docunfold.pdf-metrics file, header included
};

// Reads `pdf` with pdftotext and pdfinfo and compares it with
// <data>/ground_truth/text.txt and page.json. Throws InputError when the PDF
// is missing or poppler cannot read it, std::runtime_error when poppler's
// tools are not installed.
PdfMetricsResult MeasurePdf(const fs::path& data, const fs::path& pdf, const Json& options_record);

// One line for the log.
std::string Summary(const PdfMetricsResult& result);

}  // namespace docunfold::evaluate
