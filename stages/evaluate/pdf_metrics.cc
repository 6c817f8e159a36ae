#include "stages/evaluate/pdf_metrics.h"

#include <chrono>
#include <cmath>
#include <regex>
#include <stdexcept>
#include <vector>

#include "common/atomic_file.h"
#include "common/dataset.h"
#include "common/errors.h"
#include "common/program.h"
#include "common/subprocess.h"
#include "stages/evaluate/text_metrics.h"

namespace docunfold::evaluate {
namespace {

constexpr double kPointsPerMetre = 72 / 0.0254;

// What a poppler tool prints (stdout and stderr), or InputError naming the
// PDF with the tool's first complaint.
std::string RunPoppler(const std::vector<std::string>& argv, const fs::path& pdf) {
  std::string out;
  SubprocessOptions options;
  options.timeout_seconds = 300;
  options.on_line = [&](const std::string& line) { out += line + '\n'; };
  const SubprocessResult r = RunSubprocess(argv, options);
  if (r.not_found)
    throw std::runtime_error(argv[0] +
                             " not found: install poppler-utils (scripts/install-deps.sh)");
  if (r.timed_out) throw InputError(pdf.string() + ": " + argv[0] + " ran out of time reading it");
  if (r.exit_code != 0) {
    const std::string first = out.substr(0, out.find('\n'));
    throw InputError(pdf.string() + ": not a PDF poppler can read (" + argv[0] + ": " +
                     (first.empty() ? "exit " + std::to_string(r.exit_code) : first) + ")");
  }
  return out;
}

}  // namespace

bool HasTrueText(const fs::path& data) {
  std::error_code ec;
  return fs::is_regular_file(data / "ground_truth" / "text.txt", ec);
}

PdfMetricsResult MeasurePdf(const fs::path& data, const fs::path& pdf, const Json& options_record) {
  const auto start = std::chrono::steady_clock::now();
  std::error_code ec;
  if (!fs::is_regular_file(pdf, ec)) throw InputError(pdf.string() + ": no such file (--pdf)");
  const std::string info = RunPoppler({"pdfinfo", "-f", "1", "-l", "1", pdf.string()}, pdf);
  std::smatch m;
  static const std::regex pages_re(R"(Pages:\s+([0-9]+))");
  static const std::regex size_re(R"(Page +1 size: +([0-9.]+) x ([0-9.]+) pts)");
  const int pages = std::regex_search(info, m, pages_re) ? std::stoi(m[1]) : 0;
  if (pages < 1 || !std::regex_search(info, m, size_re))
    throw InputError(pdf.string() + ": has no page");
  const double width_pt = std::stod(m[1]), height_pt = std::stod(m[2]);
  const std::string reading = RunPoppler({"pdftotext", "-q", pdf.string(), "-"}, pdf);

  const fs::path text_file = data / "ground_truth" / "text.txt";
  const std::string truth = ReadTextFile(text_file);
  PdfMetricsResult r;
  r.words_found = WordsFound(truth, reading);
  const TextScores in_order = CompareTexts(CollapseWhitespace(truth), CollapseWhitespace(reading));
  r.cer_reading_order = in_order.cer;
  r.size_error = NAN;

  Json doc = MakeHeader("docunfold.pdf-metrics", 1, "evaluate", options_record);
  doc["data"] = data.string();
  doc["pdf"] = pdf.string();
  doc["pages"] = pages;
  Json page{{"width_mm", width_pt / kPointsPerMetre * 1000},
            {"height_mm", height_pt / kPointsPerMetre * 1000}};
  const fs::path page_json = data / "ground_truth" / "page.json";
  if (fs::is_regular_file(page_json, ec)) {
    const auto [true_w, true_h] = ReadTruePageSize(page_json);
    const double w = width_pt / kPointsPerMetre, h = height_pt / kPointsPerMetre;
    r.size_error = std::max(std::abs(w / true_w - 1), std::abs(h / true_h - 1));
    page["true_width_mm"] = true_w * 1000;
    page["true_height_mm"] = true_h * 1000;
    page["size_error"] = r.size_error;
  } else {
    page["true_width_mm"] = page["true_height_mm"] = page["size_error"] = nullptr;
  }
  doc["page"] = page;
  doc["text"] = Json{{"reference", "ground_truth/text.txt"},
                     {"words_found", r.words_found},
                     {"cer_reading_order", NumberOrNull(r.cer_reading_order)},
                     {"reference_words", in_order.reference_words},
                     {"reading_order_text", reading}};
  doc["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.document = std::move(doc);
  return r;
}

std::string Summary(const PdfMetricsResult& r) {
  std::string s = "pdf: words found " + Fixed(r.words_found, 3) + ", CER " +
                  Fixed(r.cer_reading_order, 3) + " in reading order";
  if (std::isfinite(r.size_error)) s += ", page size off by " + Fixed(100 * r.size_error, 1) + " %";
  return s;
}

}  // namespace docunfold::evaluate
