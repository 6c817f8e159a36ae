// init-mesh --sfm 10_sfm --boundary 20_boundary --out 40_init [options]
// Writes mesh3d.ply (M), mesh2d.ply (M') and init.json (see init_mesh.h).
#include <chrono>

#include "common/cli.h"
#include "stages/init-mesh/init_mesh.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CommandLine command{
      "Initial meshes of the page: a quad grid on the document region of the reference "
      "image (Coons patch of the boundary sides), lifted to 3D by the depths of the SfM "
      "points, unfolded to the plane and refined by the joint isometric optimisation "
      "without feature lines; M' is turned upright by the page border."};
  fs::path sfm_dir, boundary_dir, points_path, out_dir;
  init_mesh::Options options;
  command.RequiredPath("sfm", &sfm_dir, "sfm output: cameras.json, points.ply, reference.png");
  command.RequiredPath("boundary", &boundary_dir,
                       "segment-boundary output: boundary.json, mask.png");
  command.Path("points", &points_path,
               "3D points to fit (default: <sfm>/points.ply; densify writes 25_points/points.ply)");
  command.RequiredPath("out", &out_dir, "output directory (mesh3d.ply, mesh2d.ply, init.json)");
  init_mesh::DeclareOptions(command.table(), &options);

  return RunStage("init-mesh", command, argc, argv, [&] {
    const auto start = std::chrono::steady_clock::now();
    const init_mesh::Inputs inputs = init_mesh::ReadInputs(sfm_dir, boundary_dir, points_path);
    const double read_seconds = SecondsSince(start);
    const init_mesh::Result result = init_mesh::Run(inputs, options);
    init_mesh::LogResult(result, options);
    init_mesh::WriteOutputs(out_dir, inputs, result, options, command.Record(), read_seconds);
    const auto& its = result.refine.iterations;
    Log(std::to_string(result.meshes.grid.nx - 1) + "x" +
        std::to_string(result.meshes.grid.ny - 1) + " quads (" + result.grid_source + "), " +
        std::to_string(result.inliers) + "/" + std::to_string(result.points_in_region) +
        " points inliers, refined in " + std::to_string(its.size()) + " iterations (F " +
        std::to_string(its.front().F) + " -> " + std::to_string(its.back().F) +
        "), isometry error " + Fixed(100 * result.isometry_error_mean, 3) + " %, " +
        Fixed(SecondsSince(start), 2) + " s");
  });
}
