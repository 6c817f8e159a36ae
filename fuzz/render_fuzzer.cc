// render's render.json as the report reads it back: the map from M' to the
// rectified page, to draw optimize's lines over it (a small page, valid lines).
#include <cstddef>
#include <cstdint>
#include <exception>

#include "common/json_io.h"
#include "fuzz/fuzz_input.h"
#include "stages/report/stage_outputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using docunfold::Json;
  static const cv::Mat rectified(48, 64, CV_8UC3, cv::Scalar(255, 255, 255));
  static const Json lines = Json::parse(R"({"lines": [
    {"kind": "text", "flat": [[0.1, 0.2], [0.6, 0.25], [0.9, 0.3]]},
    {"kind": "edge", "flat": [[0.0, 0.0], [0.0, 0.8]]},
    {"kind": "side", "flat": [[0.0, 0.8], [1.0, 0.8]]}]})");
  Json doc;  // the report's TryJson: null when the file does not parse
  try {
    doc = docunfold::ReadJsonFile(docunfold::fuzz::WriteInput(data, size, "render.json"));
  } catch (const std::exception&) {
    return 0;
  }
  try {
    docunfold::report::DrawFeatureLines(rectified, doc, lines);
  } catch (const std::exception&) {
    // A clean rejection of a bad file is what the reader should do.
  }
  return 0;
}
