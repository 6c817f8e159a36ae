// ReadCameras (common/camera.h), sfm's cameras.json and the ground truth's,
// and ReadDistortion of each view, which render reads from the same file.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>

#include "common/camera.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using docunfold::Json;
  try {
    const auto path = docunfold::fuzz::WriteInput(data, size, "cameras.json");
    const docunfold::CameraSet cameras = docunfold::ReadCameras(path);
    const Json doc = docunfold::ReadJsonFile(path);
    const docunfold::JsonReader reader(doc, path);
    for (size_t i = 0; i < cameras.views.size(); ++i)
      docunfold::ReadDistortion(reader, "/views/" + std::to_string(i));
  } catch (const std::exception&) {
    // A clean rejection of a bad file is what the reader should do.
  }
  return 0;
}
