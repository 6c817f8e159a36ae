#include "tests/pdf/pdf_checks.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <sstream>

#include "stages/evaluate/image_metrics.h"
#include "stages/evaluate/ocr.h"
#include "stages/evaluate/text_metrics.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {

std::vector<PdfPage> PdfPages(const fs::path& pdf) {
  const CommandResult r =
      RunCommand("pdfinfo -f 1 -l 1000 " + Quote(pdf.string()) + " 2>/dev/null");
  std::vector<PdfPage> pages;
  if (r.exit_code != 0) return pages;
  static const std::regex size(R"(Page +[0-9]+ size: +([0-9.]+) x ([0-9.]+) pts)");
  for (std::sregex_iterator it(r.output.begin(), r.output.end(), size), end; it != end; ++it)
    pages.push_back({std::stod((*it)[1]), std::stod((*it)[2])});
  return pages;
}

namespace {

// What `pdftotext <flags> <pdf> -` writes.
std::string Pdftotext(const std::string& flags, const fs::path& pdf) {
  return RunCommand("pdftotext " + flags + " " + Quote(pdf.string()) + " - 2>/dev/null").output;
}

}  // namespace

std::string PdfText(const fs::path& pdf, int page) {
  const std::string range =
      page > 0 ? " -f " + std::to_string(page) + " -l " + std::to_string(page) : "";
  return Pdftotext("-layout" + range, pdf);
}

std::string PdfTextInReadingOrder(const fs::path& pdf) { return Pdftotext("", pdf); }

std::vector<PdfWord> PdfWords(const fs::path& pdf) {
  const std::string html = Pdftotext("-bbox -f 1 -l 1", pdf);
  static const std::regex element(
      R"re(<word xMin="([-0-9.]+)" yMin="([-0-9.]+)" xMax="([-0-9.]+)" yMax="([-0-9.]+)">([^<]*)</word>)re");
  std::vector<PdfWord> words;
  for (std::sregex_iterator it(html.begin(), html.end(), element), end; it != end; ++it) {
    const double x0 = std::stod((*it)[1]), y0 = std::stod((*it)[2]);
    words.push_back(
        {cv::Rect2d(x0, y0, std::stod((*it)[3]) - x0, std::stod((*it)[4]) - y0), (*it)[5]});
  }
  return words;
}

cv::Mat RenderPdfPage(const fs::path& pdf, int page, cv::Size size) {
  // pdftoppm draws an image at its own pixel size half a pixel off (MS-SSIM
  // 0.987 against the image even for a page of exactly its pixels at its
  // dpi): the page is drawn at twice the size and reduced by averaging.
  const fs::path out = fs::temp_directory_path() / ("pdf-page-" + std::to_string(::getpid()));
  const CommandResult r = RunCommand(
      "pdftoppm -png -singlefile -f " + std::to_string(page) + " -l " + std::to_string(page) +
      " -scale-to-x " + std::to_string(2 * size.width) + " -scale-to-y " +
      std::to_string(2 * size.height) + " " + Quote(pdf.string()) + " " + Quote(out.string()));
  cv::Mat image = r.exit_code == 0 ? cv::imread(out.string() + ".png") : cv::Mat();
  if (!image.empty()) cv::resize(image, image, size, 0, 0, cv::INTER_AREA);
  std::error_code ec;
  fs::remove(out.string() + ".png", ec);
  return image;
}

bool QpdfCheckPasses(const fs::path& pdf, std::string* output) {
  const CommandResult r = RunCommand("qpdf --check " + Quote(pdf.string()));
  if (output) *output = r.output;
  return r.exit_code == 0;
}

std::string AltoSchemaErrors(const fs::path& alto) {
  const fs::path schemas = SourceDir() / "schemas/alto";
  const CommandResult r =
      RunCommand("XML_CATALOG_FILES=" + Quote((schemas / "catalog.xml").string()) +
                 " xmllint --nonet --noout --schema " + Quote((schemas / "alto-3-0.xsd").string()) +
                 " " + Quote(alto.string()));
  return r.exit_code == 0 ? "" : r.output;
}

std::vector<AltoWord> AltoWords(const fs::path& alto) {
  std::ifstream in(alto);
  std::stringstream s;
  s << in.rdbuf();
  const std::string xml = s.str();
  static const std::regex element(R"(<(String|TextLine) ([^>]*)>)");
  static const std::regex attribute(R"re(([A-Z]+)="([^"]*)")re");
  std::vector<AltoWord> words;
  int line = -1;
  for (std::sregex_iterator it(xml.begin(), xml.end(), element), end; it != end; ++it) {
    if ((*it)[1] == "TextLine") {
      ++line;
      continue;
    }
    const std::string attrs = (*it)[2];
    AltoWord w;
    w.line = line;
    for (std::sregex_iterator a(attrs.begin(), attrs.end(), attribute); a != end; ++a) {
      const std::string key = (*a)[1], value = (*a)[2];
      if (key == "HPOS") w.box.x = std::stoi(value);
      if (key == "VPOS") w.box.y = std::stoi(value);
      if (key == "WIDTH") w.box.width = std::stoi(value);
      if (key == "HEIGHT") w.box.height = std::stoi(value);
      if (key == "WC") w.confidence = std::stod(value);
      if (key == "CONTENT") w.text = value;
    }
    words.push_back(w);
  }
  return words;
}

namespace {

// The q-quantile (0..1) of a grey image's values.
double Quantile(const cv::Mat& grey, double q) {
  std::vector<uchar> v;
  for (int r = 0; r < grey.rows; ++r)
    v.insert(v.end(), grey.ptr<uchar>(r), grey.ptr<uchar>(r) + grey.cols);
  const size_t k = std::min(v.size() - 1, size_t(q * v.size()));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

std::vector<AltoWord> WordsWithoutPrint(const cv::Mat& page, const std::vector<AltoWord>& words,
                                        double contrast) {
  cv::Mat grey;
  cv::cvtColor(page, grey, cv::COLOR_BGR2GRAY);
  std::vector<AltoWord> bare;
  const cv::Rect inside(0, 0, grey.cols, grey.rows);
  for (const AltoWord& w : words) {
    const cv::Rect box = w.box & inside;
    if (box.area() == 0) {
      bare.push_back(w);
      continue;
    }
    // The ground around the word (a photo's light varies across the page):
    // the median of the box grown by its height on every side.
    const int grow = std::max(2, w.box.height);
    const cv::Rect around =
        cv::Rect(w.box.x - grow, w.box.y - grow, w.box.width + 2 * grow, w.box.height + 2 * grow) &
        inside;
    const double ground = Quantile(grey(around), 0.5);
    const bool dark_print = Quantile(grey(box), 0.1) <= ground - contrast;
    const bool light_print = Quantile(grey(box), 0.9) >= ground + contrast;
    if (!dark_print && !light_print) bare.push_back(w);
  }
  return bare;
}

double CharacterErrorRate(const std::string& reference, const std::string& text) {
  using namespace evaluate;
  return CompareTexts(CollapseWhitespace(reference), CollapseWhitespace(text)).cer;
}

double WordsFound(const std::string& reference, const std::string& text) {
  return evaluate::WordsFound(reference, text);
}

std::string TesseractText(const fs::path& image) {
  evaluate::Ocr ocr;
  return ocr.RecognizeFile(image);
}

double MsSsimOf(const cv::Mat& a, const cv::Mat& b) {
  return evaluate::MsSsim(evaluate::MatlabGrey(a), evaluate::MatlabGrey(b)).value;
}

}  // namespace docunfold::testing
