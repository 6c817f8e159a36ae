// Checks of a PDF and its ALTO file through independent tools: poppler's
// pdfinfo, pdftotext and pdftoppm, qpdf --check, xmllint with the ALTO
// schema; shared by the pdf stage's cli and e2e tests.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace docunfold::testing {

namespace fs = std::filesystem;

struct PdfPage {
  double width_pt = 0;
  double height_pt = 0;
};

// The pages' sizes as pdfinfo reports them (empty when pdfinfo fails).
std::vector<PdfPage> PdfPages(const fs::path& pdf);

// pdftotext -layout of page `page` (1-based; 0: all pages).
std::string PdfText(const fs::path& pdf, int page = 0);

// pdftotext's text in its reading order (no -layout): what a viewer's
// select-all and copy gives.
std::string PdfTextInReadingOrder(const fs::path& pdf);

struct PdfWord {
  cv::Rect2d box;  // points, from the page's top left
  std::string text;
};
// The words of the first page as pdftotext -bbox boxes them.
std::vector<PdfWord> PdfWords(const fs::path& pdf);

// Page `page` rendered by pdftoppm at `size` pixels (BGR).
cv::Mat RenderPdfPage(const fs::path& pdf, int page, cv::Size size);

// qpdf --check passes.
bool QpdfCheckPasses(const fs::path& pdf, std::string* output = nullptr);

// xmllint against schemas/alto/alto-3-0.xsd (offline); "" when valid, else
// xmllint's output.
std::string AltoSchemaErrors(const fs::path& alto);

struct AltoWord {
  cv::Rect box;
  double confidence = 0;  // WC
  std::string text;
  int line = -1;  // the index of its <TextLine> in the file
};
// The <String> elements of an ALTO file, in its order.
std::vector<AltoWord> AltoWords(const fs::path& alto);

// The words whose box holds no print: none of its darkest tenth of pixels
// `contrast` grey levels darker than the ground around it (the median of the
// box grown by its height on every side), nor, for light print on a dark
// ground, its brightest tenth that much lighter.
std::vector<AltoWord> WordsWithoutPrint(const cv::Mat& page, const std::vector<AltoWord>& words,
                                        double contrast = 20);

// Character error rate of `text` against `reference`, whitespace collapsed.
double CharacterErrorRate(const std::string& reference, const std::string& text);

// The share of `reference`'s words (runs of ASCII letters and digits, any
// case, counted with repeats) that `text` holds too, in any order: what a
// search of the page finds, whatever order its text comes out in.
double WordsFound(const std::string& reference, const std::string& text);

// Tesseract's text of an image file (English, automatic segmentation).
std::string TesseractText(const fs::path& image);

// DocUNet's MS-SSIM of two equally sized images.
double MsSsimOf(const cv::Mat& a, const cv::Mat& b);

}  // namespace docunfold::testing
