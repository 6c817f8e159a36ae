#include "stages/evaluate/evaluate.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "common/atomic_file.h"
#include "common/camera.h"
#include "common/dataset.h"
#include "common/errors.h"
#include "common/option_table.h"
#include "common/ply.h"
#include "common/program.h"
#include "common/raster.h"
#include "stages/evaluate/geometry_metrics.h"
#include "stages/evaluate/image_metrics.h"
#include "stages/evaluate/ocr.h"
#include "stages/evaluate/registration.h"
#include "stages/evaluate/text_metrics.h"

namespace docunfold::evaluate {
namespace {

using Clock = std::chrono::steady_clock;

// FNV-1a over the file's bytes and the OCR settings: a stable cache key
// (std::hash is not stable across builds).
std::string CacheKey(const fs::path& file, const std::string& settings) {
  std::string bytes = ReadTextFile(file) + '\0' + settings;
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

Json SizeJson(cv::Size s) { return Json::array({s.width, s.height}); }

Json Skipped(const std::string& why) { return Json{{"skipped", why}}; }

// The result registered to the truth by one affine map (registration.h), the
// map given in fractions of the page (x / width, y / height) so that it reads
// the same at any size: diagonal = the result's scale of the page along x
// and y, last column = its shift.
Json RegistrationJson(const EvaluationPair& pair, const cv::Mat2f& flow, Metrics* m) {
  const std::optional<AffineRegistration> reg =
      RegisterAffine(pair.ground_truth, pair.result, flow);
  if (!reg) return Skipped("too few flow vectors on the page's ink agree on one affine map");
  m->ms_ssim_registered = reg->ms_ssim;
  const double w = pair.ground_truth.cols, h = pair.ground_truth.rows;
  auto page_map = [&](const cv::Matx23d& a) {
    return Json::array({Json::array({a(0, 0), a(0, 1) * h / w, a(0, 2) / w}),
                        Json::array({a(1, 0) * w / h, a(1, 1), a(1, 2) / h})});
  };
  Json candidates = Json::array();
  for (const AffineCandidate& c : reg->candidates)
    candidates.push_back({{"fit", c.fit},
                          {"result_from_truth", page_map(c.result_from_truth)},
                          {"samples", c.samples},
                          {"residual_px", c.residual_px},
                          {"ms_ssim", c.ms_ssim}});
  return {{"method",
           "the best affine map by MS-SSIM of those fitted to the DeepFlow field where "
           "flat.png has ink (RANSAC at 1 px of the flow size, then refined on its inliers; "
           "least squares over every such vector; RANSAC over the vectors no fit before took, "
           "up to three times) and the identity; the result resampled through it, MS-SSIM "
           "as above"},
          {"fit", reg->fit},
          {"result_from_truth", page_map(reg->result_from_truth)},
          {"units", "fractions of the page's width (x) and height (y)"},
          {"samples", reg->samples},
          {"residual_px", reg->residual_px},
          {"ms_ssim", reg->ms_ssim},
          {"candidates", candidates}};
}

// OCR of the ground truth, from the cache when it holds this file's text.
std::string GroundTruthText(Ocr& ocr, const fs::path& flat, const fs::path& work, bool use_cache,
                            bool* from_cache) {
  *from_cache = false;
  if (!use_cache || work.empty()) return ocr.RecognizeFile(flat);
  const fs::path cache =
      work / "70_eval" / "ocr-cache" / (CacheKey(flat, ocr.Description()) + ".txt");
  std::error_code ec;
  if (fs::is_regular_file(cache, ec)) {
    *from_cache = true;
    return ReadTextFile(cache);
  }
  std::string text = ocr.RecognizeFile(flat);
  try {
    EnsureDirectory(cache.parent_path());
    WriteTextAtomic(cache, text);
  } catch (const OutputError& e) {
    Log(std::string("cannot cache OCR text (") + e.what() + "); continuing");
  }
  return text;
}

Json ScoresJson(const TextScores& s) {
  return Json{{"ed", s.ed},
              {"reference_chars", s.reference_chars},
              {"result_chars", s.result_chars},
              {"cer", NumberOrNull(s.cer)},
              {"word_ed", s.word_ed},
              {"reference_words", s.reference_words},
              {"wer", NumberOrNull(s.wer)}};
}

Json EvaluateOcr(const EvaluateInputs& in, const EvaluateOptions& options,
                 const cv::Mat& result_image, cv::Size truth_size, Metrics* m) {
  Ocr ocr(options.ocr_language);
  bool cached = false;
  const fs::path flat = in.data / "ground_truth" / "flat.png";
  const std::string reference = GroundTruthText(ocr, flat, in.work, options.ocr_cache, &cached);
  const bool resize = options.ocr_at_truth_size && result_image.size() != truth_size;
  std::string result;
  if (resize) {
    cv::Mat resized;
    const bool enlarge = truth_size.area() > result_image.size().area();
    cv::resize(result_image, resized, truth_size, 0, 0, enlarge ? cv::INTER_CUBIC : cv::INTER_AREA);
    result = ocr.RecognizeImage(resized);
  } else {
    result = ocr.RecognizeFile(in.result);
  }
  const TextScores s = CompareTexts(reference, result);
  m->ed = double(s.ed);
  m->cer = s.cer;
  m->wer = s.wer;
  Json out = ScoresJson(s);
  out["engine"] = ocr.Description();
  out["reference"] = "OCR of ground_truth/flat.png";
  out["reference_from_cache"] = cached;
  out["result_text"] = result;  // what OCR read, to see why a CER is what it is
  out["result_ocr_size"] = SizeJson(resize ? truth_size : result_image.size());
  const fs::path text_file = in.data / "ground_truth" / "text.txt";
  std::error_code ec;
  if (fs::is_regular_file(text_file, ec)) {
    // text.txt has one line per text line and no paragraph gaps; OCR output
    // has both, so whitespace is normalised before this comparison.
    const std::string truth = CollapseWhitespace(ReadTextFile(text_file));
    const TextScores t = CompareTexts(truth, CollapseWhitespace(result));
    const TextScores f = CompareTexts(truth, CollapseWhitespace(reference));
    m->cer_text = t.cer;
    m->wer_text = t.wer;
    Json tj = ScoresJson(t);
    tj["reference"] = "ground_truth/text.txt, whitespace collapsed";
    tj["flat_cer"] = NumberOrNull(f.cer);  // what OCR achieves on the flat scan
    tj["flat_wer"] = NumberOrNull(f.wer);
    out["text_txt"] = tj;
  } else {
    out["text_txt"] = nullptr;
  }
  return out;
}

double PageDiagonal(const fs::path& page_json) {
  const auto [w, h] = ReadTruePageSize(page_json);
  return std::hypot(w, h);
}

Json EvaluateGeometry(const EvaluateInputs& in, const EvaluateOptions& options, Metrics* m) {
  const fs::path gt = in.data / "ground_truth";
  std::error_code ec;
  fs::path mesh_dir = options.mesh_dir;
  if (mesh_dir.empty()) {
    if (in.work.empty()) return Skipped("no work directory given");
    for (const char* stage : {"50_optimize", "40_init"}) {
      if (fs::is_regular_file(in.work / stage / "mesh3d.ply", ec)) {
        mesh_dir = in.work / stage;
        break;
      }
    }
    if (mesh_dir.empty()) return Skipped("no mesh3d.ply in 50_optimize/ or 40_init/");
  } else if (!fs::is_regular_file(mesh_dir / "mesh3d.ply", ec)) {
    throw InputError((mesh_dir / "mesh3d.ply").string() + ": no such file (--mesh-dir)");
  }
  for (const char* f : {"mesh.ply", "cameras.json", "page.json"})
    if (!fs::is_regular_file(gt / f, ec))
      return Skipped(std::string("data set has no ground_truth/") + f);
  const fs::path sfm_cameras = in.work / "10_sfm" / "cameras.json";
  if (in.work.empty() || !fs::is_regular_file(sfm_cameras, ec))
    return Skipped("no 10_sfm/cameras.json to align the meshes through");

  const PlyData mesh3d = ReadPly(mesh_dir / "mesh3d.ply");
  const PlyData truth = ReadPly(gt / "mesh.ply");
  const double diagonal = PageDiagonal(gt / "page.json");
  std::string why;
  const auto alignment =
      AlignCameras(ReadCameras(sfm_cameras), ReadCameras(gt / "cameras.json"), &why);
  Json out{{"mesh_dir", mesh_dir.string()}, {"page_diagonal_m", diagonal}};
  if (!alignment) {
    out["surface_distance"] = Skipped(why);
  } else {
    const SurfaceDistance surface(truth.vertices, Triangulate(truth.faces));
    const DistanceStats d = MeshToSurface(mesh3d.vertices, alignment->truth_from_sfm, surface);
    m->surface_mean_pct = 100 * d.mean / diagonal;
    m->surface_max_pct = 100 * d.max / diagonal;
    out["alignment"] = {{"method",
                         "similarity (Eigen::umeyama) of the camera centres of "
                         "10_sfm/cameras.json onto ground_truth/cameras.json"},
                        {"cameras", alignment->cameras},
                        {"scale", alignment->truth_from_sfm.scale},
                        {"residual_pct", 100 * alignment->rms_residual / diagonal}};
    out["surface_distance"] = {{"mean_pct", NumberOrNull(m->surface_mean_pct)},
                               {"max_pct", NumberOrNull(m->surface_max_pct)},
                               {"vertices", d.samples}};
  }
  if (fs::is_regular_file(mesh_dir / "mesh2d.ply", ec)) {
    const PlyData mesh2d = ReadPly(mesh_dir / "mesh2d.ply");
    const IsometryStats iso =
        IsometryError(mesh3d, mesh2d, (mesh_dir / "mesh3d.ply").string() + " and mesh2d.ply");
    m->isometry_mean = iso.mean;
    m->isometry_max = iso.max;
    out["isometry"] = {{"mean", iso.mean},
                       {"max", iso.max},
                       {"edges", iso.edges},
                       {"definition", "|edge length in M - in M'| / length in M'"}};
  } else {
    out["isometry"] = Skipped("no mesh2d.ply beside mesh3d.ply");
  }
  return out;
}

}  // namespace

bool HasGroundTruth(const fs::path& data) {
  std::error_code ec;
  return fs::is_regular_file(data / "ground_truth" / "flat.png", ec);
}

void DeclareOptions(OptionTable& table, EvaluateOptions* o) {
  table.Switch("front-end", &o->front_end,
               "measure 20_boundary/ and 30_features/ of --work against the ground truth "
               "instead of a rectified image");
  table.Value("method", &o->method, "label of this result (row name)");
  table.Switch("ocr", &o->ocr, "CER, ED and WER (Tesseract)");
  table.Switch("flow", &o->flow, "LD and Li-D (DeepFlow)");
  table.Switch("registered", &o->registered,
               "also MS-SSIM after registering the result to flat.png by the best single affine "
               "map (fitted to the DeepFlow field on the page's ink): the loss the crop's sides "
               "and the page's scale explain, apart from its local shape");
  table.Switch("geometry", &o->geometry, "surface distance and isometry error");
  table.Switch("ocr-cache", &o->ocr_cache,
               "cache the OCR text of flat.png in <work>/70_eval/ocr-cache/ (off: always OCR "
               "it)");
  table.Switch("ocr-at-truth-size", &o->ocr_at_truth_size,
               "OCR the result resized to flat.png's size (bicubic up, area down), so that CER "
               "does not depend on the output resolution (off: OCR the result as it is, as the "
               "literature does)");
  table.Value("lang", &o->ocr_language, "Tesseract language");
}

EvaluateResult Run(const EvaluateInputs& in, const EvaluateOptions& options,
                   const Json& options_record) {
  const auto start = Clock::now();
  const fs::path flat_path = in.data / "ground_truth" / "flat.png";
  const cv::Mat flat = ReadImage(flat_path);
  const cv::Mat result = ReadImage(in.result);
  EvaluateResult out;
  Metrics& m = out.metrics;
  Json seconds = Json::object();

  auto t = Clock::now();
  const EvaluationPair pair = PrepareEvaluationPair(flat, result);
  const MsSsimResult ms = MsSsim(pair.ground_truth, pair.result);
  m.ms_ssim = ms.value;
  seconds["ms_ssim"] = SecondsSince(t);
  Json ms_json{{"eval_size", SizeJson(pair.ground_truth.size())},
               {"scales", ms.scales},
               {"weights", kMsSsimWeights},
               {"definition",
                "DocUNet: MATLAB rgb2gray; ground truth resized (INTER_AREA) to "
                "598400 pixels keeping aspect, result to the same size; SSIM "
                "11x11 Gaussian sigma 1.5, replicated borders; 5 scales by "
                "pyrDown (reflect); weighted sum, finest scale first, weights "
                "divided by their sum 1.0001 so that identical images give 1"}};

  Json flow_json;
  cv::Mat2f flow_field;
  if (options.flow || options.registered) {
    t = Clock::now();
    flow_field = HalfSizeFlow(pair.ground_truth, pair.result);
    seconds["flow"] = SecondsSince(t);
  }
  if (options.flow) {
    const FlowResult flow = FlowStatistics(flow_field);
    m.ld = flow.ld;
    m.li_d = flow.li_d;
    flow_json = {{"method",
                  "DeepFlow (OpenCV contrib optflow), a stand-in for "
                  "the SIFT flow of the literature"},
                 {"size", SizeJson(flow.size)},
                 {"units", "pixels at the flow size (half the MS-SSIM size)"},
                 {"ld", flow.ld},
                 {"li_d", flow.li_d}};
  } else {
    flow_json = Skipped("--no-flow");
  }

  Json registration_json = Skipped("no --registered");
  if (options.registered) {
    t = Clock::now();
    registration_json = RegistrationJson(pair, flow_field, &m);
    seconds["registration"] = SecondsSince(t);
  }

  Json ocr_json;
  if (options.ocr) {
    t = Clock::now();
    ocr_json = EvaluateOcr(in, options, result, flat.size(), &m);
    seconds["ocr"] = SecondsSince(t);
  } else {
    ocr_json = Skipped("--no-ocr");
  }

  Json geometry_json;
  if (options.geometry) {
    t = Clock::now();
    geometry_json = EvaluateGeometry(in, options, &m);
    seconds["geometry"] = SecondsSince(t);
  } else {
    geometry_json = Skipped("--no-geometry");
  }
  seconds["total"] = SecondsSince(start);

  Json doc = MakeHeader("docunfold.metrics", 1, "evaluate", options_record);
  doc["method"] = options.method;
  doc["data_set"] = fs::absolute(in.data).lexically_normal().string();
  doc["result"] = in.result.string();
  doc["ground_truth"] = flat_path.string();
  doc["result_size"] = SizeJson(result.size());
  doc["ground_truth_size"] = SizeJson(flat.size());
  doc["metrics"] = {{"ms_ssim", NumberOrNull(m.ms_ssim)},
                    {"ms_ssim_registered", NumberOrNull(m.ms_ssim_registered)},
                    {"ld", NumberOrNull(m.ld)},
                    {"li_d", NumberOrNull(m.li_d)},
                    {"cer", NumberOrNull(m.cer)},
                    {"ed", std::isfinite(m.ed) ? Json(int64_t(m.ed)) : Json(nullptr)},
                    {"wer", NumberOrNull(m.wer)},
                    {"cer_text", NumberOrNull(m.cer_text)},
                    {"wer_text", NumberOrNull(m.wer_text)},
                    {"surface_mean_pct", NumberOrNull(m.surface_mean_pct)},
                    {"surface_max_pct", NumberOrNull(m.surface_max_pct)},
                    {"isometry_mean", NumberOrNull(m.isometry_mean)},
                    {"isometry_max", NumberOrNull(m.isometry_max)}};
  doc["ms_ssim"] = ms_json;
  doc["flow"] = flow_json;
  doc["registration"] = registration_json;
  doc["ocr"] = ocr_json;
  doc["geometry"] = geometry_json;
  doc["seconds"] = seconds;
  out.document = std::move(doc);
  return out;
}

std::string Summary(const EvaluateResult& r, const std::string& method) {
  const Metrics& m = r.metrics;
  auto figure = [](const char* name, double v, int decimals) {
    return std::isfinite(v) ? std::string(", ") + name + " " + Fixed(v, decimals) : std::string();
  };
  return method + ": MS-SSIM " + Fixed(m.ms_ssim, 4) +
         figure("registered by one affine map", m.ms_ssim_registered, 4) + figure("LD", m.ld, 2) +
         figure("Li-D", m.li_d, 2) + figure("CER", m.cer, 4) + figure("WER", m.wer, 4) +
         figure("surface mean %", m.surface_mean_pct, 3) + figure("isometry", m.isometry_mean, 4) +
         " (" + Fixed(r.document["seconds"]["total"].get<double>(), 1) + " s)";
}

}  // namespace docunfold::evaluate
