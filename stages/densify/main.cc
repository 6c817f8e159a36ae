// densify --data DATA --sfm 10_sfm/ --boundary 20_boundary/ --out 25_points/
// Writes points.ply, points.json and overlay.png (see densify.h).
#include "common/cli.h"
#include "stages/densify/densify.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CommandLine command{
      "Adds 3D points of the page to sfm's sparse cloud, cameras held fixed: "
      "text and print followed from the reference view into the other photos by "
      "optical flow, and the page's outline and the shading steps of its blank paper "
      "(a fold's crease) matched along epipolar lines, and print the others missed found "
      "by sweeping depth around the surface of those points. Writes "
      "points.ply (sfm's points first), points.json and overlay.png."};
  densify::DensifyOptions o;
  command.RequiredPath("data", &o.data_dir, "data set folder (its images/ are read)");
  command.RequiredPath("sfm", &o.sfm_dir, "sfm output: cameras.json, points.ply, reference.png");
  command.RequiredPath("boundary", &o.boundary, "segment-boundary output: boundary.json, mask.png");
  command.RequiredPath("out", &o.out_dir, "output directory (e.g. 25_points)");
  densify::DeclareOptions(command.table(), &o);

  return RunStage("densify", command, argc, argv, [&] {
    const densify::DensifyInputs in = densify::ReadInputs(o);
    const densify::DensifyResult r = densify::Run(in, o);
    densify::WriteOutputs(in, r, o, command.Record());
    for (const std::string& w : r.warnings) Log("warning: " + w);
    Log("wrote " + (o.out_dir / "points.ply").string() + ": " +
        std::to_string(r.sfm_points - int(r.hidden.size())) + " sfm (" +
        std::to_string(r.hidden.size()) + " hidden behind the page left out) + " +
        std::to_string(r.texture_points) + " texture + " + std::to_string(r.outline.points) +
        " outline" + (o.steps.enabled ? " + " + std::to_string(r.steps.points) + " step" : "") +
        (o.sweep.enabled ? " + " + std::to_string(r.sweep.points) + " swept" : "") + " points, " +
        Fixed(r.seconds_total, 2) + " s");
  });
}
