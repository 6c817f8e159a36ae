// Timing of the isometry library on the full schedule optimize will run:
// grid 20x30 quads, 4 rounds separated by 3 Catmull-Clark subdivisions, on a
// data set's truth (points from WriteSfmFromTruth, initial M = the truth on a
// coarse grid, flattened halfway). Not a test: prints a table.
//   isometry_bench <data set> [--method gn|lbfgs] [--solver auto|direct|cg]
//                  [--rounds 4] [--points 6000] [--flatten 0.5]
#include <chrono>
#include <cstring>
#include <ctime>
#include <iostream>
#include <string>

#include "common/isometry/isometry.h"
#include "common/isometry/metrics.h"
#include "common/isometry/subdivision.h"
#include "common/ply.h"
#include "tests/isometry/test_meshes.h"

using namespace docunfold;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: isometry_bench <data set> [--method gn|lbfgs] [--solver "
                 "auto|direct|cg] [--rounds N] [--points N] [--flatten a]\n";
    return 2;
  }
  isometry::SolveOptions o;
  int rounds = 4, points = 6000, verbose = 0;
  double flatten = 0.5;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--method")
      o.method = v == "lbfgs" ? isometry::Method::kLbfgs : isometry::Method::kGaussNewton;
    if (k == "--solver")
      o.linear_solver = v == "direct" ? isometry::LinearSolver::kDirect
                        : v == "cg"   ? isometry::LinearSolver::kConjugateGradient
                                      : isometry::LinearSolver::kAuto;
    if (k == "--rounds") rounds = std::stoi(v);
    if (k == "--points") points = std::stoi(v);
    if (k == "--flatten") flatten = std::stod(v);
    if (k == "--max-outer") o.max_outer_iterations = std::stoi(v);
    if (k == "--cg-iterations") o.cg_max_iterations = std::stoi(v);
    if (k == "--iso")
      o.iso_normalization =
          v == "raw" ? isometry::IsoNormalization::kRaw : isometry::IsoNormalization::kStrain;
    if (k == "--verbose") verbose = std::stoi(v);
    if (k == "--cg-tol") o.cg_tolerance = std::stod(v);
    if (k == "--fair2d") o.weights.fair2d = std::stod(v);
    if (k == "--threads") o.num_threads = std::stoi(v);
    if (k == "--coarse-max") o.coarse_max_vertices = std::stoi(v);
  }
  auto gt = testing::LoadGroundTruth(argv[1]);
  if (!gt) return 1;
  const std::string ref = testing::ChooseReferenceView(*gt);
  const MeshPair fine = testing::TrueMeshPair(*gt, ref);
  const double diag = gt->Diagonal() * testing::ReferenceFrame(*gt, ref).scale;
  testing::TempDir dir;
  testing::SfmFromTruthOptions so;
  so.num_points = points;
  so.noise = 0.002;
  so.outlier_fraction = 0.03;
  testing::WriteSfmFromTruth(*gt, ref, dir / "10_sfm", so);
  isometry::Problem p;
  p.points = ReadPly(dir / "10_sfm/points.ply").vertices;
  const bool wide = gt->width_m > gt->height_m;
  p.meshes = testing::Resample(fine, wide ? 31 : 21, wide ? 21 : 31);
  {  // flatten toward the mean depth plane
    double mean = 0;
    for (auto& v : p.meshes.mesh3d) mean += v.z() / p.meshes.mesh3d.size();
    for (auto& v : p.meshes.mesh3d) v.z() -= flatten * (v.z() - mean);
  }
  std::printf("%s: %zu points, reference %s\n", argv[1], p.points.size(), ref.c_str());
  std::printf(
      "round grid       iters  total_s  per_iter_s  footpt_s  step_s  lin_its  dist%%  iso_err%%  "
      "method\n");
  double total = 0, total_cpu = 0;
  for (int round = 0; round < rounds; ++round) {
    if (round > 0) p.meshes = isometry::SubdivideCatmullClark(p.meshes);
    const std::clock_t c0 = std::clock();
    const auto r = isometry::Solve(p, o);
    const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    total_cpu += cpu;
    p.meshes = r.meshes;
    if (verbose)
      for (const auto& it : r.report.iterations)
        std::printf(
            "   it %2d F %.6e iso %.3e dist %.3e f3 %.3e f2 %.3e in %d lin %d mu %.2e acc %d step "
            "%.3f\n",
            it.iteration, it.F, it.terms.iso, it.terms.dist, it.terms.fair3d, it.terms.fair2d,
            it.inliers, it.linear_iterations, it.damping, int(it.step_accepted), it.step_seconds);
    double foot = 0, step = 0;
    int lin = 0;
    for (const auto& it : r.report.iterations) {
      foot += it.footpoint_seconds;
      step += it.step_seconds;
      lin += it.linear_iterations;
    }
    const int steps = std::max<int>(1, r.report.iterations.size() - 1);
    total += r.report.seconds;
    const auto d = testing::SurfaceDistance(p.meshes, fine);
    std::printf("%5d %4dx%-4d %5zu  %7.3f  %10.4f  %8.4f  %6.3f  %7d  %5.3f  %8.4f  %6.3f  %s\n",
                round, p.meshes.grid.nx, p.meshes.grid.ny, r.report.iterations.size(),
                r.report.seconds, r.report.seconds / steps, foot / r.report.iterations.size(),
                step / steps, lin, d.mean / diag * 100,
                isometry::IsometryEdgeError(p.meshes).mean * 100, cpu, r.report.method.c_str());
  }
  std::printf("total %.3f s wall, %.3f s cpu\n", total, total_cpu);
  return 0;
}
