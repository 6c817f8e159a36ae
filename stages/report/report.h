// report: one self-contained HTML page per data set that puts every stage's
// output side by side, for a person tuning the pipeline (works offline:
// every picture is inlined, no script or network).
#pragma once

#include <filesystem>
#include <string>

#include "common/option_table_fwd.h"

namespace docunfold::report {

namespace fs = std::filesystem;

struct ReportOptions {
  fs::path data;              // data-set folder (images/, optional ground_truth/)
  fs::path work;              // its work directory (10_sfm/ ... 70_eval/)
  fs::path out;               // the HTML file, usually <work>/report.html
  int thumbnail_width = 220;  // pixels
  int figure_width = 900;     // pixels, large pictures
};

// Declares the options of ReportOptions but the paths (data, work, out).
void DeclareOptions(OptionTable& table, ReportOptions* options);

struct ReportResult {
  std::string html;
  int sections = 0;  // sections with content (a stage not run yet adds a note)
  int missing = 0;   // stages whose outputs are absent
};

// Reads whatever the work directory holds; throws InputError when the data
// set or the work directory is missing altogether.
ReportResult Run(const ReportOptions& options);

}  // namespace docunfold::report
