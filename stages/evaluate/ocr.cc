#include "stages/evaluate/ocr.h"

#include <leptonica/allheaders.h>
#include <tesseract/baseapi.h>

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <vector>

#include "common/errors.h"

namespace docunfold::evaluate {

Ocr::Ocr(const std::string& language)
    : language_(language), api_(std::make_unique<tesseract::TessBaseAPI>()) {
  // Tesseract's own diagnostics ("Estimating resolution as ...") would break
  // our one-line-a-second log style; send them nowhere.
  if (api_->Init(nullptr, language_.c_str(), tesseract::OEM_DEFAULT) != 0)
    throw std::runtime_error("Tesseract cannot load language '" + language_ +
                             "' (is tesseract-ocr-" + language_ +
                             " installed, or TESSDATA_PREFIX set?)");
  api_->SetVariable("debug_file", "/dev/null");
  api_->SetPageSegMode(tesseract::PSM_AUTO);
  setMsgSeverity(L_SEVERITY_NONE);
}

Ocr::~Ocr() {
  if (api_) api_->End();
}

std::string Ocr::RecognizeFile(const fs::path& image) {
  Pix* pix = pixRead(image.c_str());
  if (pix == nullptr) throw InputError(image.string() + ": cannot read image for OCR");
  return Recognize(pix, image.string());
}

std::string Ocr::RecognizeImage(const cv::Mat& image) {
  std::vector<uchar> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error("cannot encode an image for OCR");
  Pix* pix = pixReadMem(png.data(), png.size());
  if (pix == nullptr) throw std::runtime_error("Leptonica cannot read an encoded image");
  return Recognize(pix, "image in memory");
}

std::string Ocr::Recognize(Pix* pix, const std::string& what) {
  api_->SetImage(pix);
  char* text = api_->GetUTF8Text();
  api_->Clear();
  pixDestroy(&pix);
  if (text == nullptr) throw std::runtime_error(what + ": OCR failed");
  std::string out(text);
  delete[] text;
  out.erase(std::remove(out.begin(), out.end(), '\f'), out.end());
  return out;
}

std::string Ocr::Description() const {
  return std::string("Tesseract ") + tesseract::TessBaseAPI::Version() + ", " + language_ +
         ", psm 3";
}

}  // namespace docunfold::evaluate
