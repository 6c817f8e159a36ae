// ReadPly (common/ply.h): every mesh and point cloud the stages read back.
#include <cstddef>
#include <cstdint>
#include <exception>

#include "common/ply.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const docunfold::PlyData ply =
        docunfold::ReadPly(docunfold::fuzz::WriteInput(data, size, "mesh.ply"));
    ply.GridSize();
  } catch (const std::exception&) {
    // A clean rejection of a bad file is what the reader should do.
  }
  return 0;
}
