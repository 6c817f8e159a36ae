// Tesseract OCR (C++ API) set up like the `tesseract` command line with its
// defaults: English, automatic page segmentation (PSM 3), the page read from
// its file by Leptonica (so the file's resolution tag counts the same way).
#pragma once

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

struct Pix;  // Leptonica's image
namespace tesseract {
class TessBaseAPI;
}

namespace docunfold::evaluate {

namespace fs = std::filesystem;

class Ocr {
 public:
  // Throws std::runtime_error when the language data cannot be loaded.
  explicit Ocr(const std::string& language = "eng");
  ~Ocr();
  Ocr(const Ocr&) = delete;
  Ocr& operator=(const Ocr&) = delete;

  // UTF-8 text of an image file, form feeds removed; throws InputError when
  // the file cannot be read as an image.
  std::string RecognizeFile(const fs::path& image);

  // The same for an image in memory (8-bit BGR or grey), passed to Leptonica
  // as a PNG so that it is read exactly as a file would be.
  std::string RecognizeImage(const cv::Mat& image);

  // "Tesseract 5.3.0, eng, psm 3": what the text depends on (cache key).
  std::string Description() const;

 private:
  std::string Recognize(::Pix* pix, const std::string& what);

  std::string language_;
  std::unique_ptr<tesseract::TessBaseAPI> api_;
};

}  // namespace docunfold::evaluate
