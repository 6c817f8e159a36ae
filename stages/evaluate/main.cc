// evaluate: metrics of a rectified image against the data set's ground truth.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "common/atomic_file.h"
#include "common/cli.h"
#include "common/json_io.h"
#include "stages/evaluate/evaluate.h"
#include "stages/evaluate/front_end.h"

using namespace docunfold;

namespace {

void RunFrontEnd(const evaluate::EvaluateInputs& in, const fs::path& out) {
  if (!evaluate::HasTrueSurface(in.data)) {
    Log("note: " + in.data.string() +
        " has no true surface (ground_truth/mesh.ply, cameras.json, page.json, flat.png); "
        "nothing to measure, no metrics written");
    return;
  }
  std::error_code ec;
  if (!fs::is_regular_file(in.work / "10_sfm" / "cameras.json", ec))
    throw InputError((in.work / "10_sfm" / "cameras.json").string() + ": no such file");
  const evaluate::FrontEndResult r = evaluate::RunFrontEnd({in.data, in.work});
  EnsureDirectory(out.parent_path().empty() ? fs::path(".") : out.parent_path());
  WriteJsonAtomic(out, r.document);
  std::string summary = "front end in " + r.reference + ":";
  char buf[160];
  if (r.has_boundary) {
    std::snprintf(buf, sizeof buf,
                  " boundary IoU %.4f, worst corner %.2f %% of the diagonal, %d side(s) not real;",
                  r.boundary.iou, 100 * r.boundary.WorstCornerFraction(),
                  r.boundary.sides_not_real);
    summary += buf;
  }
  if (r.has_lines) {
    std::snprintf(buf, sizeof buf, " features precision %.3f, recall %.3f", r.lines.precision,
                  r.lines.recall);
    summary += buf;
  }
  Log(summary + " -> " + out.string());
}

}  // namespace

int main(int argc, char** argv) {
  LimitOpenMpThreads(argv);
  CLI::App app{
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
      "file (needs the true surface: ground_truth/mesh.ply, cameras.json)."};
  evaluate::EvaluateInputs in;
  evaluate::EvaluateOptions options;
  fs::path out;
  app.add_option("--data", in.data, "data set folder")->required();
  app.add_option("--work", in.work, "work directory (meshes, 10_sfm/cameras.json, OCR cache)");
  app.add_option("--result", in.result, "rectified image to evaluate (not with --front-end)");
  bool front_end = false;
  app.add_flag("--front-end", front_end,
               "measure 20_boundary/ and 30_features/ of --work against the ground "
               "truth instead of a rectified image");
  app.add_option("--out", out, "metrics JSON to write")->required();
  app.add_option("--method", options.method, "label of this result (row name)")
      ->capture_default_str();
  app.add_option("--mesh-dir", options.mesh_dir,
                 "folder with mesh3d.ply (and mesh2d.ply) to measure "
                 "(default: <work>/50_optimize, else <work>/40_init)");
  bool no_ocr = false, no_flow = false, no_geometry = false, no_cache = false;
  app.add_flag("--no-ocr", no_ocr, "skip CER, ED and WER (Tesseract)");
  app.add_flag("--no-flow", no_flow, "skip LD and Li-D (DeepFlow)");
  app.add_flag("--no-geometry", no_geometry, "skip surface distance and isometry error");
  app.add_flag("--no-ocr-cache", no_cache,
               "always OCR flat.png (default: cache its text in "
               "<work>/70_eval/ocr-cache/)");
  app.add_flag("--ocr-at-truth-size", options.ocr_at_truth_size,
               "OCR the result resized to flat.png's size (bicubic up, area "
               "down), so that CER does not depend on the output resolution "
               "(default: OCR the result as it is, as the literature does)");
  app.add_option("--lang", options.ocr_language, "Tesseract language")->capture_default_str();

  return RunStage("evaluate", app, argc, argv, [&] {
    options.ocr = !no_ocr;
    options.flow = !no_flow;
    options.geometry = !no_geometry;
    options.ocr_cache = !no_cache;
    std::error_code ec;
    if (!fs::is_directory(in.data, ec))
      throw InputError(in.data.string() + ": no such data set folder");
    if (front_end) {
      if (!in.result.empty()) throw UsageError("--result and --front-end exclude each other");
      if (in.work.empty()) throw UsageError("--front-end needs --work");
      RunFrontEnd(in, out);
      return;
    }
    if (in.result.empty()) throw UsageError("--result is required (or --front-end)");
    if (!evaluate::HasGroundTruth(in.data)) {
      Log("note: " + in.data.string() +
          " has no ground_truth/flat.png; nothing to evaluate, no metrics written");
      return;
    }
    if (!fs::is_regular_file(in.result, ec))
      throw InputError(in.result.string() + ": no such file (--result)");
    const evaluate::EvaluateResult r = evaluate::Run(in, options);
    EnsureDirectory(out.parent_path().empty() ? fs::path(".") : out.parent_path());
    WriteJsonAtomic(out, r.document);
    const auto& m = r.metrics;
    auto fmt = [](const char* name, double v, const char* f) {
      if (!std::isfinite(v)) return std::string();
      char buf[64];
      std::snprintf(buf, sizeof buf, f, v);
      return std::string(", ") + name + " " + buf;
    };
    Log(options.method + ": MS-SSIM " + fmt("", m.ms_ssim, "%.4f").substr(3) +
        fmt("LD", m.ld, "%.2f") + fmt("Li-D", m.li_d, "%.2f") + fmt("CER", m.cer, "%.4f") +
        fmt("WER", m.wer, "%.4f") + fmt("surface mean %", m.surface_mean_pct, "%.3f") +
        fmt("isometry", m.isometry_mean, "%.4f") + " (" +
        fmt("", r.document["seconds"]["total"].get<double>(), "%.1f").substr(3) + " s) -> " +
        out.string());
  });
}
