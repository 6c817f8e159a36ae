// ReadBoundary (common/page_files.h): segment-boundary's boundary.json.
#include <cstddef>
#include <cstdint>
#include <exception>

#include "common/page_files.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const docunfold::Boundary boundary =
        docunfold::ReadBoundary(docunfold::fuzz::WriteInput(data, size, "boundary.json"));
    boundary.RealSides();
  } catch (const std::exception&) {
    // A clean rejection of a bad file is what the reader should do.
  }
  return 0;
}
