// truth-frontend DATA WORK [REFERENCE] [--meshes]: writes WORK/10_sfm and
// WORK/20_boundary from DATA's ground truth (see truth_frontend.h); with
// --meshes also WORK/40_init/{mesh3d,mesh2d}.ply = the true surface and its
// flat twin, so render and evaluate can be tried on perfect meshes. Used by
// scripts/bench.sh with BENCH_FRONTEND=truth. Exit 3 when the ground truth is
// missing or unusable, 2 on bad usage.
#include <iostream>
#include <string>
#include <vector>

#include "common/atomic_file.h"
#include "tests/evaluate/truth_frontend.h"
#include "tests/support/truth_frame.h"

int main(int argc, char** argv) {
  using namespace docunfold;
  using namespace docunfold::testing;
  std::vector<std::string> args;
  bool meshes = false;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--meshes")
      meshes = true;
    else
      args.push_back(argv[i]);
  }
  if (args.size() < 2 || args.size() > 3) {
    std::cerr << "usage: truth-frontend DATA WORK [REFERENCE] [--meshes]\n";
    return 2;
  }
  try {
    auto gt = LoadGroundTruth(args[0]);
    if (!gt) {
      std::cerr << "truth-frontend: " << args[0] << ": no usable ground truth\n";
      return 3;
    }
    const fs::path work = args[1];
    const std::string ref = WriteTruthFrontEnd(*gt, work, args.size() == 3 ? args[2] : "");
    if (meshes) {
      const TrueMeshes m = TrueMeshesInReferenceFrame(*gt, ref);
      EnsureDirectory(work / "40_init");
      WritePly(work / "40_init" / "mesh3d.ply", m.mesh3d);
      WritePly(work / "40_init" / "mesh2d.ply", m.mesh2d);
    }
    std::cerr << "truth-frontend: " << work.string() << ": 10_sfm, 20_boundary"
              << (meshes ? " and 40_init" : "") << " from the truth, reference " << ref << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "truth-frontend: " << args[0] << ": " << e.what() << "\n";
    return 3;
  }
}
