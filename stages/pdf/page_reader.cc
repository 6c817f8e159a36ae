#include "stages/pdf/page_reader.h"

#include <fcntl.h>
#include <leptonica/allheaders.h>
#include <tesseract/baseapi.h>
#include <tesseract/renderer.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>

#include "common/errors.h"

namespace docunfold::pdf {
namespace {

// Tesseract prints its own lines ("Error opening data file ...") to stderr
// when a language is missing; ours is the one line the user should see.
class StderrSilenced {
 public:
  StderrSilenced() : saved_(dup(STDERR_FILENO)) {
    const int null = open("/dev/null", O_WRONLY);
    if (null >= 0) dup2(null, STDERR_FILENO), close(null);
  }
  ~StderrSilenced() {
    if (saved_ >= 0) dup2(saved_, STDERR_FILENO), close(saved_);
  }

 private:
  int saved_;
};

// "chi_sim" -> "tesseract-ocr-chi-sim", Debian's name for its data package.
std::string DebianPackage(std::string code) {
  std::replace(code.begin(), code.end(), '_', '-');
  std::transform(code.begin(), code.end(), code.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return "tesseract-ocr-" + code;
}

std::vector<std::string> SplitLanguages(const std::string& language) {
  std::vector<std::string> codes;
  std::stringstream in(language);
  for (std::string code; std::getline(in, code, '+');)
    if (!code.empty()) codes.push_back(code);
  return codes;
}

// The languages of `language` that have no .traineddata where Tesseract
// looks (TESSDATA_PREFIX, else Debian's folder).
std::vector<std::string> MissingLanguages(const std::string& language) {
  const char* prefix = std::getenv("TESSDATA_PREFIX");
  const fs::path dir = prefix && *prefix ? fs::path(prefix) : "/usr/share/tesseract-ocr/5/tessdata";
  std::vector<std::string> missing;
  std::error_code ec;
  for (const std::string& code : SplitLanguages(language))
    if (!fs::is_regular_file(dir / (code + ".traineddata"), ec)) missing.push_back(code);
  return missing;
}

}  // namespace

void PageReader::PixDeleter::operator()(void* pix) const {
  Pix* p = static_cast<Pix*>(pix);
  pixDestroy(&p);
}

PageReader::PageReader(const std::string& language)
    : language_(language), api_(std::make_unique<tesseract::TessBaseAPI>()) {
  if (SplitLanguages(language).empty()) throw UsageError("--lang: no language given");
  int status;
  {
    StderrSilenced quiet;
    status = api_->Init(nullptr, language.c_str(), tesseract::OEM_DEFAULT);
  }
  if (status != 0) {
    std::vector<std::string> missing = MissingLanguages(language);
    if (missing.empty()) missing = SplitLanguages(language);
    std::string packages;
    for (const std::string& code : missing)
      packages += (packages.empty() ? "" : " ") + DebianPackage(code);
    throw InputError("Tesseract has no data for language '" + missing.front() +
                     "': install the Debian package " + packages + " (or set TESSDATA_PREFIX)");
  }
  // Tesseract's diagnostics ("Line cannot be recognized!!") go nowhere: our
  // log is one plain line at a time.
  api_->SetVariable("debug_file", "/dev/null");
  setMsgSeverity(L_SEVERITY_NONE);
}

PageReader::~PageReader() {
  if (api_) api_->End();
}

PageReader::PageReader(PageReader&&) noexcept = default;
PageReader& PageReader::operator=(PageReader&&) noexcept = default;

PageReader::Page PageReader::Read(const cv::Mat& image, Segmentation segmentation) {
  api_->SetPageSegMode(segmentation == Segmentation::kSingleColumn ? tesseract::PSM_SINGLE_COLUMN
                       : segmentation == Segmentation::kSingleLine ? tesseract::PSM_SINGLE_LINE
                                                                   : tesseract::PSM_AUTO);
  // Through a PNG, so that Leptonica reads it exactly as it reads the file.
  std::vector<uchar> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error("cannot encode the page for OCR");
  Pix* pix = pixReadMem(png.data(), png.size());
  if (pix == nullptr) throw std::runtime_error("Leptonica cannot read the encoded page");
  pix_.reset(pix);
  api_->SetImage(pix);
  if (api_->Recognize(nullptr) != 0) throw std::runtime_error("Tesseract failed to read the page");

  Page page;
  std::unique_ptr<tesseract::ResultIterator> it(api_->GetIterator());
  if (!it) return page;
  int block = -1;
  int line = -1;  // index in page.lines of the line being read (-1: it has no baseline)
  do {
    if (it->Empty(tesseract::RIL_WORD)) continue;
    if (it->IsAtBeginningOf(tesseract::RIL_BLOCK)) ++block;
    int x0, y0, x1, y1, bx0, by0, bx1, by1;
    if (it->IsAtBeginningOf(tesseract::RIL_TEXTLINE)) {
      line = -1;
      if (it->BoundingBox(tesseract::RIL_TEXTLINE, &x0, &y0, &x1, &y1) &&
          it->Baseline(tesseract::RIL_TEXTLINE, &bx0, &by0, &bx1, &by1)) {
        page.lines.push_back({std::max(block, 0),
                              cv::Rect(x0, y0, x1 - x0, y1 - y0),
                              {double(bx0), double(by0)},
                              {double(bx1), double(by1)}});
        line = int(page.lines.size()) - 1;
      }
    }
    if (!it->BoundingBox(tesseract::RIL_WORD, &x0, &y0, &x1, &y1)) continue;
    std::unique_ptr<char[]> text(it->GetUTF8Text(tesseract::RIL_WORD));
    if (!text || !*text.get()) continue;
    page.words.push_back({cv::Rect(x0, y0, x1 - x0, y1 - y0),
                          it->Confidence(tesseract::RIL_WORD) / 100.0, text.get(), line});
  } while (it->Next(tesseract::RIL_WORD));
  return page;
}

void PageReader::Write(const fs::path& base, const fs::path& image_file, int ppi,
                       const std::string& title) {
  if (!pix_) throw std::logic_error("PageReader::Write before Read");
  api_->SetInputName(image_file.c_str());
  // Tesseract takes ownership of the input image: it gets a reference of its own.
  api_->SetInputImage(pixClone(static_cast<Pix*>(pix_.get())));
  api_->SetSourceResolution(ppi);
  auto renderer =
      std::make_unique<tesseract::TessPDFRenderer>(base.c_str(), api_->GetDatapath(), true);
  renderer->insert(new tesseract::TessAltoRenderer(base.c_str()));
  renderer->insert(new tesseract::TessHOcrRenderer(base.c_str()));
  if (!renderer->happy()) throw OutputError(base.string() + ".pdf: cannot write");
  if (!renderer->BeginDocument(title.c_str()) || !renderer->AddImage(api_.get()) ||
      !renderer->EndDocument())
    throw std::runtime_error(base.string() + ": Tesseract could not write the PDF page");
}

bool PageReader::IsDictionaryWord(const std::string& word) const {
  return api_->IsValidWord(word.c_str()) != 0;
}

std::string PageReader::Version() { return tesseract::TessBaseAPI::Version(); }

}  // namespace docunfold::pdf
