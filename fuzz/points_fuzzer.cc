// densify's points.json as the report reads it back (its counts).
#include <cstddef>
#include <cstdint>
#include <exception>

#include "common/json_io.h"
#include "fuzz/fuzz_input.h"
#include "stages/report/stage_outputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  docunfold::Json doc;  // the report's TryJson: null when the file does not parse
  try {
    doc = docunfold::ReadJsonFile(docunfold::fuzz::WriteInput(data, size, "points.json"));
  } catch (const std::exception&) {
    return 0;
  }
  try {
    docunfold::report::PointsCounts(doc);
  } catch (const std::exception&) {
    // A clean rejection of a bad file is what the reader should do.
  }
  return 0;
}
