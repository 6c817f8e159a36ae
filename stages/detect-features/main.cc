// detect-features --image reference.png --mask 20_boundary/mask.png --out 30_features/
// Writes features.json and overlay.png (see detect_features.h).
#include <chrono>
#include <opencv2/imgcodecs.hpp>

#include "common/atomic_file.h"
#include "common/cli.h"
#include "stages/detect-features/detect_features.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CommandLine command{
      "Finds short, locally straight feature segments in the document region of "
      "the reference image: text baselines (kind text) and centre lines of printed "
      "rules (kind edge). Writes features.json and overlay.png."};
  fs::path image_path, mask_path, out_dir;
  features::FeaturesOptions opt;
  command.RequiredPath("image", &image_path, "reference image (e.g. 10_sfm/reference.png)");
  command.RequiredPath("mask", &mask_path, "document region, 255 = page (20_boundary/mask.png)");
  command.RequiredPath("out", &out_dir, "output directory (e.g. 30_features)");
  features::DeclareOptions(command.table(), &opt);

  return RunStage("detect-features", command, argc, argv, [&] {
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
                                             image.rows, command.Record()));
    Log(std::to_string(result.text_segments) + " text and " + std::to_string(result.edge_segments) +
        " edge segments (text height " + std::to_string(int(std::lround(result.text_height))) +
        " px), " + Fixed(SecondsSince(start), 2) + " s");
  });
}
