// segment-boundary --image reference.png --out 20_boundary/
// Writes mask.png, boundary.json and overlay.png (see segment_boundary.h).
#include <chrono>
#include <opencv2/imgcodecs.hpp>

#include "common/atomic_file.h"
#include "common/camera.h"
#include "common/cli.h"
#include "stages/segment-boundary/segment_boundary.h"

using namespace docunfold;

namespace {

// One other view's page, as written to <out>/views/<photo name>/.
struct ViewOutput {
  fs::path dir;
  cv::Mat1b mask;
  cv::Mat overlay;
  Json doc;
};

// The page in every view of `cameras_path` but the reference. A view without
// a page is logged and left out (render uses whichever views it finds); a
// photo that is missing or not the size cameras.json says fails. `views`
// receives how many views were tried.
std::vector<ViewOutput> SegmentOtherViews(const fs::path& views_dir, const fs::path& cameras_path,
                                          const fs::path& out_dir,
                                          const boundary::BoundaryOptions& opt, int* views) {
  std::vector<ViewOutput> outputs;
  *views = 0;
  const CameraSet cameras = ReadCameras(cameras_path);
  for (const PinholeCamera& view : cameras.views) {
    if (view.image == cameras.reference) continue;
    ++*views;
    const fs::path photo = views_dir / view.image;
    const cv::Mat view_image = ReadViewPhoto(photo, view, cameras_path, 1 /*cv::IMREAD_COLOR*/);
    boundary::BoundaryResult result;
    try {
      result = boundary::SegmentBoundary(view_image, opt);
    } catch (const InputError& e) {
      Log(photo.string() + ": " + e.what() + "; view left out");
      continue;
    }
    outputs.push_back(
        {out_dir / "views" / fs::path(view.image).stem(), result.mask,
         boundary::DrawBoundaryOverlay(view_image, result, 800),
         boundary::BoundaryToJson(result, view.image, view_image.cols, view_image.rows, opt)});
  }
  return outputs;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Finds the page in the reference image: its region (mask.png), outline, "
      "corners and sides (boundary.json, real sides vs sides cut by the image "
      "border) and an overlay.png to check them at a glance."};
  fs::path image_path, out_dir;
  boundary::BoundaryOptions opt;
  app.add_option("--image", image_path, "reference image (e.g. 10_sfm/reference.png)")->required();
  app.add_option("--out", out_dir, "output directory (e.g. 20_boundary)")->required();
  app.add_option("--work-size", opt.work_size,
                 "long side (px) of the downscaled image the page is found on")
      ->capture_default_str()
      ->check(CLI::Range(64, 8192));
  app.add_option("--frame-fraction", opt.frame_fraction,
                 "width of the image frame that teaches the background colour, as a "
                 "fraction of the short side")
      ->capture_default_str()
      ->check(CLI::Range(0.005, 0.3));
  app.add_option("--table-distance", opt.table_distance,
                 "colour distance (std. deviations of the background) beyond which a "
                 "pixel is not background")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 100.0));
  app.add_option("--weak-table-distance", opt.weak_table_distance,
                 "pixels this far from the background (but not --table-distance) are "
                 "page where they touch it in areas --weak-min-width wide (e.g. the "
                 "shaded panel of a fold); set it to --table-distance to turn off")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 100.0));
  app.add_option("--weak-min-width", opt.weak_min_width,
                 "smallest width (px of the downscaled image) of such an area")
      ->capture_default_str()
      ->check(CLI::Range(1, 101));
  app.add_option("--min-area", opt.min_area_fraction,
                 "smallest page area, as a fraction of the image")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--border-tolerance", opt.border_tolerance_px,
                 "outline within this many pixels of the image border is cut off")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 50.0));
  app.add_option("--max-cut-fraction", opt.max_cut_fraction,
                 "a side with more of its length on the image border is not real")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--contour-epsilon", opt.contour_epsilon_px,
                 "Douglas-Peucker tolerance (px) of the stored outline and sides")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 20.0));
  app.add_option("--orientation", opt.orientation,
                 "which side is the top: auto (text if it tells, else geometry), text, "
                 "geometry")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "text", "geometry"}));
  app.add_flag("--verbose", opt.verbose, "log each step and its time");
  fs::path views_dir, cameras_path;
  auto* views_opt = app.add_option(
      "--views", views_dir,
      "folder of the photos (e.g. <data>/images): also find the page in every other view "
      "that --cameras registers, into <out>/views/<photo name>/ (render looks there past "
      "the border of a reference image that cuts the page off)");
  auto* cameras_opt =
      app.add_option("--cameras", cameras_path, "sfm's cameras.json (with --views)");
  views_opt->needs(cameras_opt);
  cameras_opt->needs(views_opt);

  return RunStage("segment-boundary", app, argc, argv, [&] {
    const auto start = std::chrono::steady_clock::now();
    const cv::Mat image = ReadImage(image_path, 1 /*cv::IMREAD_COLOR*/);
    if (opt.verbose)
      Log("read " + image_path.string() + " (" + std::to_string(image.cols) + "x" +
          std::to_string(image.rows) + ") in " + std::to_string(SecondsSince(start)) + " s");
    boundary::BoundaryResult result;
    try {
      result = boundary::SegmentBoundary(image, opt);
    } catch (const InputError& e) {
      throw InputError(image_path.string() + ": " + e.what());
    }
    if (opt.verbose)
      Log("page found in " + std::to_string(SecondsSince(start)) + " s; orientation by " +
          result.orientation.method);
    // The other views, all found before anything is written.
    int views = 0;
    const std::vector<ViewOutput> view_outputs =
        views_dir.empty() ? std::vector<ViewOutput>{}
                          : SegmentOtherViews(views_dir, cameras_path, out_dir, opt, &views);
    EnsureDirectory(out_dir);
    const Json doc = boundary::BoundaryToJson(result, image_path.filename().string(), image.cols,
                                              image.rows, opt);
    // Fast PNG compression: the mask compresses well anyway, the overlay is
    // for a quick look.
    const std::vector<int> png_fast = {cv::IMWRITE_PNG_COMPRESSION, 1};
    WriteImageAtomic(out_dir / "mask.png", result.mask, png_fast);
    WriteImageAtomic(out_dir / "overlay.png", boundary::DrawBoundaryOverlay(image, result),
                     png_fast);
    WriteJsonAtomic(out_dir / "boundary.json", doc);
    // Views of an earlier run would no longer match this boundary.
    std::error_code ec;
    fs::remove_all(out_dir / "views", ec);
    for (const ViewOutput& v : view_outputs) {
      EnsureDirectory(v.dir);
      WriteImageAtomic(v.dir / "mask.png", v.mask, png_fast);
      WriteImageAtomic(v.dir / "overlay.png", v.overlay, png_fast);
      WriteJsonAtomic(v.dir / "boundary.json", v.doc);
    }
    if (!views_dir.empty())
      Log("page found in " + std::to_string(view_outputs.size()) + " of " + std::to_string(views) +
          " other views");
    int real = 0;
    for (const auto& s : result.sides) real += s.real;
    Log("page covers " + std::to_string(int(std::lround(result.area_fraction * 100))) +
        "% of the image, " + std::to_string(real) + " of 4 sides real, top by " +
        result.orientation.method + ", " + std::to_string(SecondsSince(start)).substr(0, 4) + " s");
  });
}
