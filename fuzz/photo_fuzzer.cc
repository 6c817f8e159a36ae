// DecodePhoto (common/photo.h) on any bytes, as gray and as colour: the photo
// reader every stage uses, with its own JPEG decoding (libjpeg, damage
// detection), EXIF parsing (libexif) and HEIF decoding (libheif).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string_view>

#include "common/photo.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  for (const auto color : {docunfold::PhotoColor::kBgr, docunfold::PhotoColor::kGray}) {
    try {
      docunfold::DecodePhoto(bytes, "photo", color);
    } catch (const std::exception&) {
      // A clean rejection of a damaged or foreign file is what the reader should do.
    }
  }
  return 0;
}
