// sfm --data <data set> --out <dir> [--ref <image>] [options]
// COLMAP on the photos; cameras.json, points.ply, reference.png and colmap/
// in --out (see sfm.h).
#include "common/cli.h"
#include "stages/sfm/sfm.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CLI::App app{
      "Recovers the cameras and a sparse point cloud of the page with COLMAP (CPU SIFT, "
      "every pair of views matched exactly and verified, incremental mapper: the same photos "
      "give the same result on every run), picks the reference view (the one that "
      "sees the whole page and resolves its worst-seen part best) unless --ref names it, and "
      "writes "
      "cameras.json, points.ply and the undistorted reference.png in the reference "
      "camera's frame scaled to median depth 1, plus COLMAP's workspace in colmap/. "
      "Exit codes: 0 ok, 1 COLMAP missing or failing, 2 usage, 3 bad input (data set, "
      "image, --ref, too few views registered or points), 4 cannot write."};
  sfm::SfmOptions o;
  app.add_option("--data", o.data_dir, "data set folder (photos in its images/)")->required();
  app.add_option("--out", o.out_dir,
                 "output folder, e.g. work/set01/10_sfm (replaced "
                 "as a whole when the run succeeds)")
      ->required();
  app.add_option("--ref", o.reference,
                 "image name of the reference view (e.g. view_02.jpg); default: automatic");
  app.add_option("--max-image-size", o.max_image_size,
                 "long side (px) of the copies features are found on; keypoints and "
                 "reference.png stay at full resolution")
      ->capture_default_str()
      ->check(CLI::Range(100, 100000));
  app.add_option("--max-features", o.max_num_features, "SIFT features per image")
      ->capture_default_str()
      ->check(CLI::Range(100, 1000000));
  app.add_option("--camera-model", o.camera_model, "COLMAP camera model shared by all photos")
      ->capture_default_str()
      ->check(CLI::IsMember({"SIMPLE_PINHOLE", "PINHOLE", "SIMPLE_RADIAL", "RADIAL"}));
  app.add_flag("--refine-distortion,!--no-refine-distortion", o.refine_distortion,
               "refine the radial distortion in bundle adjustment (default: on; off "
               "keeps it at 0)");
  app.add_option("--max-reprojection-error", o.max_reprojection_error,
                 "the mapper drops observations farther than this from their point "
                 "(px at matching resolution; COLMAP's own default is 4)")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 100.0));
  app.add_flag("--two-view-tracks,!--no-two-view-tracks", o.two_view_tracks,
               "also triangulate points only two views see (default: on; COLMAP's "
               "own default is off)");
  app.add_option("--matcher", o.matcher,
                 "exact: brute-force SIFT matching under COLMAP's criteria, verified by "
                 "COLMAP (the same photos give the same result on every run); colmap: "
                 "COLMAP's exhaustive_matcher (FLANN: a few matches differ between runs)")
      ->capture_default_str()
      ->check(CLI::IsMember({"exact", "colmap"}));
  app.add_flag("!--no-retry", o.retry,
               "do not retry the mapper with other settings when its result is "
               "implausible (views missing, focal length off, too few points)");
  app.add_option("--min-points", o.min_points, "fewer 3D points than this is an error (exit 3)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000000));
  app.add_option("--threads", o.threads, "threads COLMAP may use; -1 = all cores")
      ->capture_default_str()
      ->check(CLI::Range(-1, 1024));
  app.add_option("--timeout", o.timeout_seconds,
                 "seconds each COLMAP command may take before it is stopped")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e6));
  app.add_option("--colmap", o.colmap, "COLMAP executable (name in PATH or a path)")
      ->capture_default_str();
  app.add_flag("--verbose", o.verbose,
               "echo COLMAP's output on stderr (it always goes to colmap/*.log)");

  return RunStage("sfm", app, argc, argv, [&] {
    const sfm::SfmResult r = sfm::RunSfm(o);
    Log(std::to_string(r.cameras.views.size()) + "/" + std::to_string(r.images.size()) +
        " views registered, " + std::to_string(r.points.size()) + " points, " + r.camera_model +
        " focal " + std::to_string(int(r.colmap_params[0] + 0.5)) + " px, reference " +
        r.reference + " (" + r.reference_choice + "), " +
        std::to_string(int(r.seconds_total + 0.5)) + " s; wrote " + o.out_dir.string());
  });
}
