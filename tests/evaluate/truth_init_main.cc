// truth-init DATA WORK OUT: writes OUT/{mesh3d,mesh2d}.ply, the true surface
// of DATA on the grid of WORK/40_init in the frame of WORK/10_sfm (see
// truth_init.h), for optimize --init OUT. Used by scripts/bench.sh for its
// docunfold-from-truth row. Exit 3 when an input is missing or unusable, 4
// when OUT cannot be written, 2 on bad usage.
#include <iostream>
#include <string>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "tests/evaluate/truth_init.h"

int main(int argc, char** argv) {
  using namespace docunfold;
  using namespace docunfold::testing;
  if (argc != 4) {
    std::cerr << "usage: truth-init DATA WORK OUT\n";
    return 2;
  }
  const fs::path data = argv[1], work = argv[2], out = argv[3];
  try {
    const auto gt = LoadGroundTruth(data);
    if (!gt) {
      std::cerr << "truth-init: " << data.string() << ": no usable ground truth\n";
      return 3;
    }
    const CameraSet cameras = ReadCameras(work / "10_sfm" / "cameras.json");
    const MeshPair init = ReadMeshPair(work / "40_init");
    const MeshPair truth = TrueSurfaceOnGrid(*gt, cameras, init);
    MeshPairWriteOptions options;
    if (const PinholeCamera* reference = cameras.Find(cameras.reference)) {
      options.reference_camera = *reference;
      options.reference_image = work / "10_sfm" / "reference.png";
    }
    options.comments = {"truth-init: the true surface of " + data.string() + " on " +
                        std::to_string(init.grid.nx) + "x" + std::to_string(init.grid.ny) +
                        " vertices, in sfm's frame"};
    try {
      EnsureDirectory(out);
      WriteMeshPair(out, truth, options);
    } catch (const OutputError& e) {
      std::cerr << "truth-init: " << e.what() << "\n";
      return 4;
    }
    std::cerr << "truth-init: " << out.string() << ": the true surface on " << init.grid.nx << "x"
              << init.grid.ny << " vertices\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "truth-init: " << data.string() << ": " << e.what() << "\n";
    return 3;
  }
}
