// baseline: reference methods of the benchmark (homography, the oracles).
#include "common/atomic_file.h"
#include "common/cli.h"
#include "stages/baseline/baseline.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CLI::App app{
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
  OptionTable table(app);
  baseline::BaselineInputs in;
  baseline::BaselineOptions options;
  fs::path out;
  table.Path("data", &in.data, "data set folder")->required();
  table.Path("work", &in.work, "work directory with 10_sfm/ (and 20_boundary/)")->required();
  table.Path("out", &out, "image to write (.png)")->required();
  baseline::DeclareOptions(table, &options);

  return RunStage("baseline", table, argc, argv, [&] {
    const baseline::BaselineResult r = baseline::Run(in, options);
    EnsureDirectory(out.parent_path().empty() ? fs::path(".") : out.parent_path());
    WriteImageAtomic(out, r.image);
    Log(r.summary + " -> " + out.string());
  });
}
