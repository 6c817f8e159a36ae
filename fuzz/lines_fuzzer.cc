// optimize's lines.json, both places it is read back: render's deskew
// (ReadLinesFile) and the report's drawing and count of the lines over a
// rectified page (a small one, with a valid render.json).
#include <cstddef>
#include <cstdint>
#include <exception>

#include "common/json_io.h"
#include "fuzz/fuzz_input.h"
#include "stages/render/lines_file.h"
#include "stages/report/stage_outputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using docunfold::Json;
  static const cv::Mat rectified(48, 64, CV_8UC3, cv::Scalar(255, 255, 255));
  static const Json render = Json::parse(R"({
    "inputs": {"meshes": "work/set01/50_optimize"}, "rotation_deg": 1.5,
    "pixels_per_unit": 60, "crop": {"x0": 0.1, "y0": 0.2},
    "orientation": {"quarter_turns_clockwise": 1}})");
  const auto path = docunfold::fuzz::WriteInput(data, size, "lines.json");
  try {
    docunfold::render::ReadLinesFile(path);
  } catch (const std::exception&) {
    // A clean rejection of a bad file is what the reader should do.
  }
  Json doc;  // the report's TryJson: null when the file does not parse
  try {
    doc = docunfold::ReadJsonFile(path);
  } catch (const std::exception&) {
  }
  try {
    docunfold::report::DrawFeatureLines(rectified, render, doc);
    docunfold::report::LinesNote(doc);
  } catch (const std::exception&) {
  }
  return 0;
}
