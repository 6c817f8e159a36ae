// evaluate: metrics of a rectified image against the data set's ground truth.
#include "common/atomic_file.h"
#include "common/cli.h"
#include "common/json_io.h"
#include "stages/evaluate/evaluate.h"
#include "stages/evaluate/front_end.h"
#include "stages/evaluate/pdf_metrics.h"

using namespace docunfold;

namespace {

void WriteDocument(const fs::path& out, const Json& document) {
  EnsureDirectory(out.parent_path().empty() ? fs::path(".") : out.parent_path());
  WriteJsonAtomic(out, document);
}

void FrontEnd(const evaluate::EvaluateInputs& in, const fs::path& out, const Json& record) {
  if (!in.result.empty()) throw UsageError("--result and --front-end exclude each other");
  if (in.work.empty()) throw UsageError("--front-end needs --work");
  if (!evaluate::HasTrueSurface(in.data)) {
    Log("note: " + in.data.string() +
        " has no true surface (ground_truth/mesh.ply, cameras.json, page.json, flat.png); "
        "nothing to measure, no metrics written");
    return;
  }
  std::error_code ec;
  if (!fs::is_regular_file(in.work / "10_sfm" / "cameras.json", ec))
    throw InputError((in.work / "10_sfm" / "cameras.json").string() + ": no such file");
  const evaluate::FrontEndResult r = evaluate::RunFrontEnd({in.data, in.work}, record);
  WriteDocument(out, r.document);
  Log(evaluate::Summary(r) + " -> " + out.string());
}

void Pdf(const evaluate::EvaluateInputs& in, const fs::path& pdf, const fs::path& out,
         const Json& record) {
  if (!in.result.empty()) throw UsageError("--result and --pdf exclude each other");
  if (!evaluate::HasTrueText(in.data)) {
    Log("note: " + in.data.string() +
        " has no ground_truth/text.txt; nothing to measure the PDF against, no metrics written");
    return;
  }
  const evaluate::PdfMetricsResult r = evaluate::MeasurePdf(in.data, pdf, record);
  WriteDocument(out, r.document);
  Log(evaluate::Summary(r) + " -> " + out.string());
}

}  // namespace

int main(int argc, char** argv) {
  LimitOpenMpThreads(argv);
  CommandLine command{
      "Compares a rectified image with <data>/ground_truth/flat.png: MS-SSIM "
      "(DocUNet definition), LD and Li-D (DeepFlow), CER/ED/WER (Tesseract, "
      "eng), and, when the work directory has meshes and the data set a true "
      "surface, the surface distance and isometry error. Writes a "
      "docunfold.metrics JSON file. A data set without ground_truth/flat.png "
      "is skipped with a note (exit 0, nothing written). Tesseract runs "
      "single-threaded (OMP_THREAD_LIMIT=1 unless set): faster on few cores.\n"
      "With --front-end it judges the pipeline's front end instead: "
      "<work>/20_boundary (page region IoU, corners, real sides) and "
      "<work>/30_features (segment precision and recall against the page's "
      "true lines) in sfm's reference view, as a docunfold.front-end-metrics "
      "file (needs the true surface: ground_truth/mesh.ply, cameras.json).\n"
      "With --pdf it judges the pipeline's searchable PDF instead: its text "
      "layer as poppler's pdftotext extracts it (words a search finds, CER in "
      "reading order) against ground_truth/text.txt, and its "
      "page size against ground_truth/page.json, as a docunfold.pdf-metrics "
      "file."};
  evaluate::EvaluateInputs in;
  evaluate::EvaluateOptions options;
  fs::path out, pdf;
  command.RequiredPath("data", &in.data, "data set folder");
  command.Path("work", &in.work, "work directory (meshes, 10_sfm/cameras.json, OCR cache)");
  command.Path("result", &in.result, "rectified image to evaluate (not with --front-end)");
  command.Path("pdf", &pdf,
               "searchable PDF to measure (80_pdf/<name>.pdf; not with --result or --front-end)");
  command.RequiredPath("out", &out, "metrics JSON to write");
  command.Path("mesh-dir", &options.mesh_dir,
               "folder with mesh3d.ply (and mesh2d.ply) to measure (default: <work>/50_optimize, "
               "else <work>/40_init)");
  evaluate::DeclareOptions(command.table(), &options);

  return RunStage("evaluate", command, argc, argv, [&] {
    std::error_code ec;
    if (!fs::is_directory(in.data, ec))
      throw InputError(in.data.string() + ": no such data set folder");
    if (options.front_end && !pdf.empty())
      throw UsageError("--front-end and --pdf exclude each other");
    if (options.front_end) return FrontEnd(in, out, command.Record());
    if (!pdf.empty()) return Pdf(in, pdf, out, command.Record());
    if (in.result.empty()) throw UsageError("--result is required (or --front-end)");
    if (!evaluate::HasGroundTruth(in.data)) {
      Log("note: " + in.data.string() +
          " has no ground_truth/flat.png; nothing to evaluate, no metrics written");
      return;
    }
    if (!fs::is_regular_file(in.result, ec))
      throw InputError(in.result.string() + ": no such file (--result)");
    const evaluate::EvaluateResult r = evaluate::Run(in, options, command.Record());
    WriteDocument(out, r.document);
    Log(evaluate::Summary(r, options.method) + " -> " + out.string());
  });
}
