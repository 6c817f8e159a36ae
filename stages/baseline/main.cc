// baseline: reference methods of the benchmark (homography, the oracles).
#include "common/atomic_file.h"
#include "common/cli.h"
#include "stages/baseline/baseline.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CommandLine command{
      "Reference methods for the benchmark. homography: "
      "<work>/10_sfm/reference.png warped by the four page corners of "
      "<work>/20_boundary/boundary.json onto a rectangle of the page's aspect "
      "(ground_truth/page.json, else estimated from the corners and K). "
      "oracle: the photo images/<reference> textured through the TRUE surface "
      "and camera (ground_truth/mesh.ply, cameras.json) at the size of "
      "flat.png: the ceiling for any method that textures from one view. "
      "oracle-multiview: the true surface textured from every photo through the "
      "true cameras by render's texture fusion: the ceiling for texturing from "
      "all the photos. With --crop-to-seen, only the part of the page some photo "
      "sees."};
  baseline::BaselineInputs in;
  baseline::BaselineOptions options;
  fs::path out;
  command.RequiredPath("data", &in.data, "data set folder");
  command.RequiredPath("work", &in.work, "work directory with 10_sfm/ (and 20_boundary/)");
  command.RequiredPath("out", &out, "image to write (.png)");
  baseline::DeclareOptions(command.table(), &options);

  return RunStage("baseline", command, argc, argv, [&] {
    const baseline::BaselineResult r = baseline::Run(in, options);
    EnsureDirectory(out.parent_path().empty() ? fs::path(".") : out.parent_path());
    WriteImageAtomic(out, r.image);
    Log(r.summary + " -> " + out.string());
  });
}
