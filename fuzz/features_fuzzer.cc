// ReadFeatures (common/page_files.h): detect-features' features.json, or any
// other detector's.
#include <cstddef>
#include <cstdint>
#include <exception>

#include "common/page_files.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    docunfold::ReadFeatures(docunfold::fuzz::WriteInput(data, size, "features.json"));
  } catch (const std::exception&) {
    // A clean rejection of a bad file is what the reader should do.
  }
  return 0;
}
