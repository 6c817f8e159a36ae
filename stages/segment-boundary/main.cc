// segment-boundary --image reference.png --out 20_boundary/
// Writes mask.png, boundary.json and overlay.png (see segment_boundary.h).
#include <chrono>
#include <opencv2/imgcodecs.hpp>

#include "common/atomic_file.h"
#include "common/cli.h"
#include "stages/segment-boundary/segment_boundary.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CommandLine command{
      "Finds the page in the reference image: its region (mask.png), outline, "
      "corners and sides (boundary.json, real sides vs sides cut by the image "
      "border) and an overlay.png to check them at a glance."};
  fs::path image_path, out_dir;
  boundary::BoundaryOptions opt;
  boundary::OtherViews views;
  command.RequiredPath("image", &image_path, "reference image (e.g. 10_sfm/reference.png)");
  command.RequiredPath("out", &out_dir, "output directory (e.g. 20_boundary)");
  boundary::DeclareOptions(command.table(), &opt, &views);

  return RunStage("segment-boundary", command, argc, argv, [&] {
    const auto start = std::chrono::steady_clock::now();
    const cv::Mat image = ReadImage(image_path, cv::IMREAD_COLOR);
    if (opt.verbose)
      Log("read " + image_path.string() + " (" + std::to_string(image.cols) + "x" +
          std::to_string(image.rows) + ") in " + Fixed(SecondsSince(start), 3) + " s");
    boundary::BoundaryResult result;
    try {
      result = boundary::SegmentBoundary(image, opt);
    } catch (const InputError& e) {
      throw InputError(image_path.string() + ": " + e.what());
    }
    if (opt.verbose)
      Log("page found in " + Fixed(SecondsSince(start), 3) + " s; orientation by " +
          result.orientation.method);
    // The other views, all found before anything is written.
    const Json record = command.Record();
    int tried = 0;
    const std::vector<boundary::BoundaryFiles> view_files =
        views.views_dir.empty() ? std::vector<boundary::BoundaryFiles>{}
                                : boundary::SegmentOtherViews(views, out_dir, opt, record, &tried);
    boundary::WriteBoundaryFiles(
        {out_dir, result.mask, boundary::DrawBoundaryOverlay(image, result),
         boundary::BoundaryToJson(result, image_path.filename().string(), image.cols, image.rows,
                                  record)},
        view_files);
    if (!views.views_dir.empty())
      Log("page found in " + std::to_string(view_files.size()) + " of " + std::to_string(tried) +
          " other views");
    int real = 0;
    for (const auto& s : result.sides) real += s.real;
    Log("page covers " + std::to_string(int(std::lround(result.area_fraction * 100))) +
        "% of the image, " + std::to_string(real) + " of 4 sides real, top by " +
        result.orientation.method + ", " + Fixed(SecondsSince(start), 2) + " s");
  });
}
