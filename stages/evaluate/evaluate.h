// evaluate: compares a rectified image with the data set's flat scan
// (ground_truth/flat.png) by the metrics of the document-dewarping
// literature (MS-SSIM, LD and Li-D, CER/ED/WER), and, when the work directory
// has meshes and the data set a true surface, measures the geometry too.
#pragma once

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>

#include "common/json_io.h"
#include "common/option_table_fwd.h"

namespace docunfold::evaluate {

namespace fs = std::filesystem;

struct EvaluateOptions {
  // Judge the front end (20_boundary/, 30_features/ of the work directory,
  // front_end.h) instead of a rectified image.
  bool front_end = false;
  std::string method = "docunfold";  // label of the row in the benchmark
  bool ocr = true;                   // CER, ED, WER with Tesseract (the slowest part, ~seconds)
  bool flow = true;                  // LD, Li-D with DeepFlow (~seconds)
  // Also MS-SSIM after registering the result to flat.png by the best
  // single affine map (registration.h): how much of the loss is the crop's
  // sides and the page's scale, not its local shape. A diagnostic, off by
  // default (the literature's figures do not register).
  bool registered = false;
  bool geometry = true;  // surface distance and isometry error, when possible
  // Meshes to measure; empty = <work>/50_optimize, else <work>/40_init.
  fs::path mesh_dir;
  // Keep the OCR text of flat.png in <work>/70_eval/ocr-cache/, keyed by a
  // hash of the file and the OCR settings, so several rows of one data set
  // read the ground truth once.
  bool ocr_cache = true;
  std::string ocr_language = "eng";
  // OCR the result resized to flat.png's size (bicubic up, area down), so
  // that CER measures the geometry and not the output resolution a method
  // picked (text at a photo's density is too small for Tesseract). Off by
  // default: the literature OCRs results as they are.
  bool ocr_at_truth_size = false;
};

// Declares every option of EvaluateOptions but mesh_dir (a path, declared
// with the other paths by main).
void DeclareOptions(OptionTable& table, EvaluateOptions* options);

struct EvaluateInputs {
  fs::path data;    // data set folder (with ground_truth/flat.png)
  fs::path work;    // work directory; may be empty (no geometry, no cache)
  fs::path result;  // the rectified image
};

// True when `data` has ground_truth/flat.png, i.e. something to compare with.
bool HasGroundTruth(const fs::path& data);

// Figures are NaN when not computed (the JSON then holds null).
struct Metrics {
  double ms_ssim = NAN;
  double ms_ssim_registered = NAN;  // with --registered
  double ld = NAN, li_d = NAN;
  double cer = NAN, wer = NAN;
  double ed = NAN;
  double cer_text = NAN, wer_text = NAN;  // against ground_truth/text.txt
  double surface_mean_pct = NAN, surface_max_pct = NAN;
  double isometry_mean = NAN, isometry_max = NAN;
};

struct EvaluateResult {
  Metrics metrics;
  Json document;  // the whole docunfold.metrics file, header included
};

// Computes every metric the options and inputs allow; the document's
// producer records `options_record`. Throws InputError for a missing or
// unreadable input (result, flat.png, meshes named by the options, malformed
// ground truth).
EvaluateResult Run(const EvaluateInputs& inputs, const EvaluateOptions& options,
                   const Json& options_record);

// One line for the log: the method and its figures (those computed) and the
// time taken.
std::string Summary(const EvaluateResult& result, const std::string& method);

}  // namespace docunfold::evaluate
