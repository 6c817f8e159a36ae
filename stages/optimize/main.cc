// optimize: the joint isometric optimisation of M and M' with feature lines.
#include <cstdio>

#include "common/cli.h"
#include "stages/optimize/optimize.h"
#include "stages/optimize/optimize_io.h"

int main(int argc, char** argv) {
  using namespace docunfold;
  CommandLine command{
      "optimize: jointly optimises the 3D page M and its flat twin M' under the isometry "
      "constraint, fitted to the SfM points, with text lines, table rules and the real page "
      "sides straightened in M' (Luo & Bo). Writes <out>/mesh3d.ply, mesh2d.ply, lines.json, "
      "log.json, scene.glb and round0/ ... roundK/."};
  optimize::InputPaths paths;
  fs::path out;
  command.RequiredPath("sfm", &paths.sfm, "10_sfm/ (cameras.json, points.ply, reference.png)");
  command.RequiredPath("boundary", &paths.boundary, "20_boundary/ or its boundary.json");
  command.RequiredPath("features", &paths.features, "feature segments (docunfold.features)");
  command.RequiredPath("init", &paths.init, "40_init/ (mesh3d.ply, mesh2d.ply)");
  command.Path("points", &paths.points,
               "3D points to fit (default: <sfm>/points.ply; densify writes 25_points/points.ply)");
  command.RequiredPath("out", &out, "output folder, e.g. 50_optimize");
  optimize::OptimizeOptions o;
  optimize::DeclareOptions(command.table(), &o);
  optimize::OutputOptions output;
  optimize::DeclareOutputOptions(command.table(), &output);

  return RunStage("optimize", command, argc, argv, [&] {
    const optimize::OptimizeInputs in = optimize::ReadInputs(paths, o.mask_hull);
    const optimize::OptimizeResult r = optimize::Run(in, o);
    optimize::WriteOutputs(out, paths, in, r, command.Record(), output);
    char buf[200];
    std::snprintf(buf, sizeof buf, "wrote %s: %dx%d grid after %zu rounds, %zu lines, %.1f s",
                  out.c_str(), r.meshes.grid.nx, r.meshes.grid.ny, r.rounds.size(),
                  r.rounds.back().lines.size(), r.seconds);
    Log(buf);
  });
}
