// detect-features --image reference.png --mask 20_boundary/mask.png --out 30_features/
// Writes features.json and overlay.png (see detect_features.h).
#include <chrono>
#include <opencv2/imgcodecs.hpp>

#include "common/atomic_file.h"
#include "common/cli.h"
#include "stages/detect-features/detect_features.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CLI::App app{
      "Finds short, locally straight feature segments in the document region of "
      "the reference image: text baselines (kind text) and centre lines of printed "
      "rules (kind edge). Writes features.json and overlay.png."};
  fs::path image_path, mask_path, out_dir;
  features::FeaturesOptions opt;
  app.add_option("--image", image_path, "reference image (e.g. 10_sfm/reference.png)")->required();
  app.add_option("--mask", mask_path, "document region, 255 = page (20_boundary/mask.png)")
      ->required();
  app.add_option("--out", out_dir, "output directory (e.g. 30_features)")->required();
  app.add_option("--margin", opt.margin_px,
                 "pixels kept from the region's outline; 0 = 0.6% of the image diagonal")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--sauvola-window", opt.sauvola_window,
                 "binarisation window (px); 0 = 1.5% of the image diagonal")
      ->capture_default_str()
      ->check(CLI::Range(0, 1001));
  app.add_option("--sauvola-k", opt.sauvola_k, "Sauvola's k")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 1.0));
  app.add_option("--straightness", opt.straightness_px,
                 "text: cut a baseline where it leaves a line by more than this (px)...")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 20.0));
  app.add_option("--straightness-rel", opt.straightness_rel,
                 "...or by this fraction of the text height, if larger")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--straightness-window", opt.straightness_window,
                 "text: judge the bend on the baseline's running median over this many text "
                 "heights either way (0 = on every sample)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--max-gap", opt.max_gap, "text: largest gap chained, in text heights")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 10.0));
  app.add_option("--min-text-length", opt.min_text_length,
                 "text: shortest segment, in text heights")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--min-length", opt.min_length_px, "shortest segment of any kind (px)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10000.0));
  app.add_option("--join-gap", opt.join_gap,
                 "join LSD pieces of one straight edge across gaps up to this many px (or "
                 "half a text height); 0 = off")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--lsd-upscale", opt.lsd_upscale,
                 "run LSD on the region enlarged this many times (thin rules); 0 = 2 when "
                 "the text is under 12 px high and the region under 4 MP, else 1")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 4.0));
  app.add_flag("--step-edges", opt.step_edges,
               "also keep single step edges (colour fields, shading), not only thin lines");
  app.add_flag("--verbose", opt.verbose, "log each step and its time");

  return RunStage("detect-features", app, argc, argv, [&] {
    const auto start = std::chrono::steady_clock::now();
    const cv::Mat image = ReadImage(image_path, cv::IMREAD_COLOR);
    const cv::Mat mask = ReadImage(mask_path, cv::IMREAD_GRAYSCALE);
    features::FeaturesResult result;
    try {
      result = features::DetectFeatures(image, mask, opt);
    } catch (const InputError& e) {
      throw InputError(mask_path.string() + ": " + e.what());
    }
    EnsureDirectory(out_dir);
    WriteImageAtomic(out_dir / "overlay.png", features::DrawFeaturesOverlay(image, mask, result),
                     {cv::IMWRITE_PNG_COMPRESSION, 1});
    WriteJsonAtomic(out_dir / "features.json",
                    features::FeaturesToJson(result, image_path.filename().string(), image.cols,
                                             image.rows, opt));
    Log(std::to_string(result.text_segments) + " text and " + std::to_string(result.edge_segments) +
        " edge segments (text height " + std::to_string(int(std::lround(result.text_height))) +
        " px), " + std::to_string(SecondsSince(start)).substr(0, 4) + " s");
  });
}
