// sfm --data <data set> --out <dir> [--ref <image>] [options]
// COLMAP on the photos; cameras.json, points.ply, reference.png and colmap/
// in --out (see sfm.h).
#include "common/cli.h"
#include "stages/sfm/sfm.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CommandLine command{
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
  command.RequiredPath("data", &o.data_dir, "data set folder (photos in its images/)");
  command.RequiredPath(
      "out", &o.out_dir,
      "output folder, e.g. work/set01/10_sfm (replaced as a whole when the run succeeds)");
  sfm::DeclareOptions(command.table(), &o);

  return RunStage("sfm", command, argc, argv, [&] {
    const sfm::SfmResult r = sfm::RunSfm(o, command.Record());
    Log(std::to_string(r.cameras.views.size()) + "/" + std::to_string(r.photos.photos.size()) +
        " views registered" +
        (r.photos.left_out.empty() ? "" : " (" + r.photos.LeftOutSummary() + ")") + ", " +
        std::to_string(r.points.size()) + " points, " + r.camera_model + ", reference " +
        r.reference + " (" + r.reference_choice + ", focal " +
        std::to_string(int(r.cameras.Find(r.reference)->K(0, 0) + 0.5)) + " px), " +
        std::to_string(int(r.seconds_total + 0.5)) + " s; wrote " + o.out_dir.string());
  });
}
