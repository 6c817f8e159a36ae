// Tesseract (C++ API) reading one page and writing what it read through its
// own renderers: a PDF page of the invisible text layer on the words, ALTO
// XML and hOCR.
#pragma once

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "stages/pdf/text_size.h"

namespace tesseract {
class TessBaseAPI;
}

namespace docunfold::pdf {

namespace fs = std::filesystem;

class PageReader {
 public:
  // `language`: Tesseract's, e.g. "eng" or "eng+deu". Throws InputError
  // naming the Debian package when a language's data is not installed.
  explicit PageReader(const std::string& language);
  ~PageReader();
  PageReader(const PageReader&) = delete;
  PageReader& operator=(const PageReader&) = delete;
  // Moved, it takes its page last read along.
  PageReader(PageReader&&) noexcept;
  PageReader& operator=(PageReader&&) noexcept;

  const std::string& language() const { return language_; }

  // How Tesseract finds the text: its automatic page segmentation (blocks,
  // columns, pictures), the page as one column of text of any size, or the
  // image as a single line of text.
  enum class Segmentation { kAuto, kSingleColumn, kSingleLine };

  // Reads `image` (8-bit BGR or grey) as the tesseract command reads a PNG
  // of it (the resolution estimated from the text), and returns its words
  // and lines.
  struct Page {
    std::vector<Word> words;
    std::vector<TextLine> lines;
  };
  Page Read(const cv::Mat& image, Segmentation segmentation = Segmentation::kAuto);

  // Writes <base>.pdf (the text layer alone, the page as large as the image
  // read at `ppi` pixels per inch), <base>.xml (ALTO) and <base>.hocr for the
  // page last read; the last two name `image_file` as their image.
  void Write(const fs::path& base, const fs::path& image_file, int ppi, const std::string& title);

  // Whether `word` is in the language's dictionary (Tesseract's word lists).
  bool IsDictionaryWord(const std::string& word) const;

  // "5.3.0"
  static std::string Version();

 private:
  std::string language_;
  std::unique_ptr<tesseract::TessBaseAPI> api_;
  struct PixDeleter {
    void operator()(void* pix) const;
  };
  std::unique_ptr<void, PixDeleter> pix_;
};

}  // namespace docunfold::pdf
