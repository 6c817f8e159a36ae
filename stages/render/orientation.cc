#include "stages/render/orientation.h"

#include <leptonica/allheaders.h>
#include <tesseract/baseapi.h>

#include <algorithm>
#include <cctype>
#include <memory>
#include <opencv2/imgproc.hpp>

namespace docunfold::render {
namespace {

// Words of at least three letters read with a confidence of 70 or more:
// upside-down or sideways text gives few of them.
int ReadableWords(tesseract::TessBaseAPI* api, const cv::Mat1b& grey) {
  api->SetImage(grey.data, grey.cols, grey.rows, 1, int(grey.step));
  api->SetSourceResolution(150);
  if (api->Recognize(nullptr) != 0) return 0;
  std::unique_ptr<tesseract::ResultIterator> it(api->GetIterator());
  int words = 0;
  if (!it) return 0;
  do {
    std::unique_ptr<char[]> text(it->GetUTF8Text(tesseract::RIL_WORD));
    if (!text) continue;
    int letters = 0;
    for (const char* c = text.get(); *c; ++c)
      letters += std::isalpha(static_cast<unsigned char>(*c)) != 0;
    if (letters >= 3 && it->Confidence(tesseract::RIL_WORD) >= 70) ++words;
  } while (it->Next(tesseract::RIL_WORD));
  return words;
}

// How much more the ink varies from row to row than from column to column:
// lines of text alternate ink and gaps along the direction across them.
double RowOverColumnContrast(const cv::Mat1b& grey) {
  cv::Mat1b ink;
  cv::adaptiveThreshold(grey, ink, 1, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY_INV, 31, 15);
  cv::Mat1f rows, cols;
  cv::reduce(ink, rows, 1, cv::REDUCE_SUM, CV_32F);
  cv::reduce(ink, cols, 0, cv::REDUCE_SUM, CV_32F);
  auto contrast = [](const cv::Mat1f& p) {
    cv::Scalar mean, sd;
    cv::meanStdDev(p, mean, sd);
    return sd[0] / (mean[0] + 1e-9);
  };
  return contrast(rows) / (contrast(cols) + 1e-9);
}

}  // namespace

cv::Mat Turn(const cv::Mat& image, int quarter_turns) {
  cv::Mat out;
  switch (((quarter_turns % 4) + 4) % 4) {
    case 1:
      cv::rotate(image, out, cv::ROTATE_90_CLOCKWISE);
      break;
    case 2:
      cv::rotate(image, out, cv::ROTATE_180);
      break;
    case 3:
      cv::rotate(image, out, cv::ROTATE_90_COUNTERCLOCKWISE);
      break;
    default:
      out = image.clone();
  }
  return out;
}

Orientation FindOrientation(const cv::Mat& image, const OrientationOptions& o) {
  Orientation r;
  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else
    grey = image;
  const double scale = double(o.read_size) / std::max(grey.cols, grey.rows);
  cv::resize(grey, grey, cv::Size(), scale, scale, scale < 1 ? cv::INTER_AREA : cv::INTER_CUBIC);
  // The window with the most ink among nine placements (a receipt's middle
  // is blank between the item names and the prices).
  const int w = int(grey.cols * o.centre_fraction), h = int(grey.rows * o.centre_fraction);
  cv::Mat1b ink;
  cv::adaptiveThreshold(grey, ink, 1, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY_INV, 31, 15);
  cv::Rect window((grey.cols - w) / 2, (grey.rows - h) / 2, w, h);
  double most = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const cv::Rect r(i * (grey.cols - w) / 2, j * (grey.rows - h) / 2, w, h);
      const double sum = cv::sum(ink(r))[0];
      if (sum > most) {
        most = sum;
        window = r;
      }
    }
  const cv::Mat1b centre = grey(window).clone();

  tesseract::TessBaseAPI api;
  if (api.Init(nullptr, "eng", tesseract::OEM_LSTM_ONLY) != 0) {
    r.note = "Tesseract's English data is missing (tesseract-ocr-eng); orientation left as is";
    return r;
  }
  api.SetPageSegMode(tesseract::PSM_SINGLE_BLOCK);
  api.SetVariable("debug_file", "/dev/null");
  // Lines of text run across the rows or the columns: read only the two
  // turns that make them horizontal, unless that is unclear.
  using Lines = OrientationOptions::Lines;
  Lines lines = o.lines;
  if (lines == Lines::kUnknown) {
    const double contrast = RowOverColumnContrast(centre);
    if (contrast > o.line_direction_ratio) lines = Lines::kAlongRows;
    if (contrast < 1 / o.line_direction_ratio) lines = Lines::kAlongColumns;
  }
  for (int k = 0; k < 4; ++k) {
    const bool sideways = k % 2 == 1;
    if (lines == Lines::kAlongRows && sideways) continue;
    if (lines == Lines::kAlongColumns && !sideways) continue;
    cv::Mat1b turned = Turn(centre, k);
    r.words[k] = ReadableWords(&api, turned);
  }
  const int best = int(std::max_element(r.words.begin(), r.words.end()) - r.words.begin());
  int second = 0;
  for (int k = 0; k < 4; ++k)
    if (k != best) second = std::max(second, r.words[k]);
  if (r.words[best] >= o.min_words && r.words[best] >= o.margin * second) {
    r.quarter_turns = best;
    r.decided = true;
  } else {
    r.note = "too little readable text to tell which way up the page is";
  }
  return r;
}

}  // namespace docunfold::render
