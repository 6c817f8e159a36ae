// baseline: reference methods of the benchmark (homography, oracle).
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
      "flat.png: the ceiling for any method that textures from one view; with "
      "--crop-to-seen, only the part of the page some photo sees."};
  baseline::BaselineInputs in;
  baseline::BaselineOptions options;
  std::string method;
  fs::path out;
  app.add_option("--method", method, "homography or oracle")
      ->required()
      ->check(CLI::IsMember({"homography", "oracle"}));
  app.add_option("--data", in.data, "data set folder")->required();
  app.add_option("--work", in.work, "work directory with 10_sfm/ (and 20_boundary/)")->required();
  app.add_option("--out", out, "image to write (.png)")->required();
  app.add_option("--width", options.width,
                 "output width in pixels, height from the page aspect (default 0: "
                 "the size of flat.png, else the page's width in the reference view)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--quarter-turns", options.quarter_turns,
                 "homography: turn the page clockwise this many quarter turns first (bench "
                 "passes 60_render/render.json's orientation.quarter_turns_clockwise, so it "
                 "reads the same way up as docunfold's result)")
      ->capture_default_str()
      ->check(CLI::Range(0, 3));
  app.add_flag("--crop-to-seen", options.crop_to_seen,
               "oracle: keep the smallest rectangle of the page that holds all of it any photo "
               "sees (ground_truth/cameras.json): the ceiling for a method that cannot know "
               "where a page cut off in every photo ends; the plain oracle where the page is "
               "seen whole");
  std::string shading = "keep";
  app.add_option("--shading", shading,
                 "remove: divide out the light's shading afterwards, as render --shading "
                 "remove does (the ceiling for such results); keep: as photographed")
      ->capture_default_str()
      ->check(CLI::IsMember({"keep", "remove"}));

  return RunStage("baseline", app, argc, argv, [&] {
    options.method = method == "oracle" ? baseline::Method::kOracle : baseline::Method::kHomography;
    options.remove_shading = shading == "remove";
    if (options.crop_to_seen && options.method != baseline::Method::kOracle)
      throw UsageError("--crop-to-seen applies to --method oracle only");
    const baseline::BaselineResult r = baseline::Run(in, options);
    EnsureDirectory(out.parent_path().empty() ? fs::path(".") : out.parent_path());
    WriteImageAtomic(out, r.image);
    Log(r.summary + " -> " + out.string());
  });
}
