// optimize: the joint isometric optimisation of M and M' with feature lines.
#include <cstdio>

#include "common/cli.h"
#include "stages/optimize/optimize.h"
#include "stages/optimize/optimize_io.h"

int main(int argc, char** argv) {
  using namespace docunfold;
  CLI::App app{
      "optimize: jointly optimises the 3D page M and its flat twin M' under the isometry "
      "constraint, fitted to the SfM points, with text lines, table rules and the real page "
      "sides straightened in M' (Luo & Bo). Writes <out>/mesh3d.ply, mesh2d.ply, lines.json, "
      "log.json, scene.glb and round0/ ... roundK/."};
  OptionTable table(app);
  optimize::InputPaths paths;
  fs::path out;
  table.Path("sfm", &paths.sfm, "10_sfm/ (cameras.json, points.ply, reference.png)")->required();
  table.Path("boundary", &paths.boundary, "20_boundary/ or its boundary.json")->required();
  table.Path("features", &paths.features, "feature segments (docunfold.features)")->required();
  table.Path("init", &paths.init, "40_init/ (mesh3d.ply, mesh2d.ply)")->required();
  table.Path("points", &paths.points,
             "3D points to fit (default: <sfm>/points.ply; densify writes 25_points/points.ply)");
  table.Path("out", &out, "output folder, e.g. 50_optimize")->required();
  optimize::OptimizeOptions o;
  optimize::DeclareOptions(table, &o);
  optimize::OutputOptions output;
  optimize::DeclareOutputOptions(table, &output);

  return RunStage("optimize", table, argc, argv, [&] {
    const optimize::OptimizeInputs in = optimize::ReadInputs(paths, o.mask_hull);
    const optimize::OptimizeResult r = optimize::Run(in, o);
    optimize::WriteOutputs(out, paths, in, r, table.Record(), output);
    char buf[200];
    std::snprintf(buf, sizeof buf, "wrote %s: %dx%d grid after %zu rounds, %zu lines, %.1f s",
                  out.c_str(), r.meshes.grid.nx, r.meshes.grid.ny, r.rounds.size(),
                  r.rounds.back().lines.size(), r.seconds);
    Log(buf);
  });
}
