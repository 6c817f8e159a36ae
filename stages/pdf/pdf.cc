#include "stages/pdf/pdf.h"

#include <leptonica/allheaders.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/markup.h"
#include "common/option_table.h"
#include "common/program.h"
#include "common/shading.h"
#include "common/statistics.h"
#include "stages/pdf/contrast.h"
#include "stages/pdf/decimal_marks.h"
#include "stages/pdf/markup_scale.h"
#include "stages/pdf/pdf_file.h"
#include "stages/pdf/ruling.h"
#include "stages/pdf/unread_print.h"
#include "stages/pdf/word_reread.h"

namespace docunfold::pdf {
namespace {

// A word whose box fits in a square a quarter of an em across is no glyph
// (a hyphen is a third of an em wide, a letter half an em tall); painted
// out with this much paper around it, in at most this many passes.
constexpr double kSpeckSideEm = 0.25;
constexpr double kSpeckMarginEm = 0.1;
constexpr int kSpeckPasses = 2;
// Tesseract reads print best at about 30 px to the em. Enlarged to
// --ocr-long-side, small print can stay below 20 px (r04's 17 px: 57 % of
// its words read; set01's 22 px: 97 %): such a page is read again enlarged
// to 30 px to the em (r04: 99 %), its long side at most 6000 px.
constexpr double kMinReadEmPx = 20;
constexpr double kReadEmPx = 30;
constexpr double kMaxReadLongSide = 6000;
// Where Tesseract's automatic segmentation leaves more than this share of the
// print unread (set07's receipt: its column of prices, 51 %; r09's lines in
// a shadow, 39 %; every text page of the bench below 10 %), the page is read
// again two other ways, one kept when it leaves at least kMinUnreadGain less.
constexpr double kMaxUnreadPrint = 0.3;
constexpr double kMinUnreadGain = 0.1;
// The chromaticity distance within which a shadow counts as paper when the
// page is read again (ShadingOptions::max_chroma_distance: 0.01).
constexpr double kTintedShadowChroma = 0.04;
// A page whose rules cover at least this share of its pixels (set02's and
// r02's tables: 11-12 %; set04's and set06's 4-5 %; an underline or the
// crop's edge: under 0.1 %), read with them, leaving more than this share of
// its print unread (set02 32 %, r02 35 %; set04 8 %, set06 0.4 %), is read
// without them too: Tesseract boxes a table's cells as tall blocks of rules
// and glyphs where the rules touch the print.
constexpr double kMinRuleShare = 0.005;
constexpr double kMaxUnreadPrintOfRuledPage = 0.15;
// Tesseract can also read the rules themselves as words, which cover the
// print but with little confidence (set02 rendered from every photo: mean
// confidence 0.55, 14 % unread, words found 27 %). A ruled page read with a
// mean confidence below this is read without its rules too, and that
// reading kept where its confidence is at least kMinConfidenceGainOfRules
// higher and it leaves at most kMaxUnreadLossOfSurerReading more print unread.
constexpr double kMinConfidenceOfRuledPage = 0.8;
constexpr double kMinConfidenceGainOfRules = 0.1;
// Tesseract's line recogniser misreads pale, thin print (set07's receipt:
// "Lig" for "7.37", words found 72 %) and reads it with little confidence. A
// page read with a mean confidence below this is read again with its print
// stretched to black, and that reading kept where its mean confidence is at
// least kMinConfidenceGain higher and it leaves at most
// kMaxUnreadLossOfSurerReading more print unread.
constexpr double kMaxConfidenceToStretch = 0.92;
constexpr double kMinConfidenceGain = 0.02;
// A reading kept for its confidence (without the rules, or stretched) may
// leave at most this much more of the print unread.
constexpr double kMaxUnreadLossOfSurerReading = 0.02;

// A folder inside `out` for what Tesseract and qpdf write before it is
// renamed into place; removed however Run ends.
class Staging {
 public:
  explicit Staging(const fs::path& out) : dir_(out / (".pdf-staging-" + std::to_string(getpid()))) {
    RemoveLeftBehind(out, ".pdf-staging-");
    std::error_code ec;
    fs::remove_all(dir_, ec);
    if (!fs::create_directories(dir_, ec))
      throw OutputError(dir_.string() + ": cannot create (" + ec.message() + ")");
  }
  ~Staging() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
};

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": Tesseract wrote no file");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// `text` with every `from` replaced by `to`.
std::string ReplaceAll(std::string text, const std::string& from, const std::string& to) {
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

void Rename(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::rename(from, to, ec);
  if (ec) throw OutputError(to.string() + ": cannot write (" + ec.message() + ")");
}

void WriteBytes(const fs::path& path, const void* data, size_t size) {
  std::ofstream f(path, std::ios::binary);
  f.write(static_cast<const char*>(data), std::streamsize(size));
  if (!f.flush()) throw OutputError(path.string() + ": cannot write");
}

// The page image as the PDF embeds it, and beside it as the file the ALTO
// names: a JPEG; for black-and-white 1-bit CCITT G4 data (Leptonica's
// encoder) and a G4 TIFF.
PageImage EncodePageImage(const cv::Mat& image, bool black_white, int quality,
                          const fs::path& file) {
  PageImage encoded;
  encoded.width = image.cols;
  encoded.height = image.rows;
  if (!black_white) {
    std::vector<uchar> jpeg;
    if (!cv::imencode(".jpg", image, jpeg,
                      {cv::IMWRITE_JPEG_QUALITY, quality, cv::IMWRITE_JPEG_OPTIMIZE, 1}))
      throw std::runtime_error("cannot encode the page as JPEG");
    encoded.data.assign(jpeg.begin(), jpeg.end());
    WriteBytes(file, jpeg.data(), jpeg.size());
    return encoded;
  }
  encoded.encoding = PageImage::Encoding::kCcittG4;
  std::vector<uchar> png;
  cv::imencode(".png", image, png);
  Pix* grey = pixReadMem(png.data(), png.size());
  Pix* bits = grey ? pixConvertTo1(grey, 128) : nullptr;
  L_COMP_DATA* g4 = nullptr;
  const bool ok = bits && pixGenerateCIData(bits, L_G4_ENCODE, 0, 0, &g4) == 0 && g4 &&
                  pixWrite(file.c_str(), bits, IFF_TIFF_G4) == 0;
  if (ok) encoded.data.assign(reinterpret_cast<const char*>(g4->datacomp), g4->nbytescomp);
  l_CIDataDestroy(&g4);
  pixDestroy(&grey);
  pixDestroy(&bits);
  if (!ok) throw OutputError(file.string() + ": cannot encode the page as G4");
  return encoded;
}

cv::Mat BlackOnWhite(const cv::Mat& even) {
  cv::Mat bw;
  cv::threshold(Grey(even), bw, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  return bw;
}

const char* EnhanceName(Enhance e) {
  switch (e) {
    case Enhance::kEvenLight:
      return "even-light";
    case Enhance::kBlackWhite:
      return "black-white";
    default:
      return "none";
  }
}

// Words and lines read from a copy of the page enlarged by 1 / `scale`, in
// the page's own pixels.
void ScaleToPage(double scale, PageReader::Page* page) {
  if (scale == 1) return;
  // Down for the start, up for the end: a box still covers what it boxed.
  auto rect = [scale](const cv::Rect& r) {
    const int x0 = int(std::floor(r.x * scale)), y0 = int(std::floor(r.y * scale));
    return cv::Rect(x0, y0, int(std::ceil((r.x + r.width) * scale)) - x0,
                    int(std::ceil((r.y + r.height) * scale)) - y0);
  };
  for (Word& w : page->words) w.box = rect(w.box);
  for (TextLine& l : page->lines) {
    l.box = rect(l.box);
    l.baseline_start *= scale;
    l.baseline_end *= scale;
  }
}

// `page` enlarged (bicubic) by `scale` >= 1.
cv::Mat Enlarged(const cv::Mat& page, double scale) {
  if (scale <= 1) return page;
  cv::Mat out;
  cv::resize(page, out,
             cv::Size(int(std::lround(page.cols * scale)), int(std::lround(page.rows * scale))), 0,
             0, cv::INTER_CUBIC);
  return out;
}

cv::Rect Grown(const cv::Rect& r, int margin) {
  return cv::Rect(r.x - margin, r.y - margin, r.width + 2 * margin, r.height + 2 * margin);
}

// `image` with each box (grown by `margin` pixels) filled with the median
// colour of a ring as wide around it: the paper a speck lies on.
cv::Mat WithoutSpecks(const cv::Mat& image, const std::vector<cv::Rect>& specks, int margin) {
  cv::Mat out = image.clone();
  const cv::Rect whole(0, 0, image.cols, image.rows);
  const int channels = image.channels();
  for (const cv::Rect& speck : specks) {
    const cv::Rect inner = Grown(speck, margin) & whole;
    if (inner.empty()) continue;
    const cv::Rect outer = Grown(inner, margin) & whole;
    std::vector<std::vector<double>> ring(channels);
    for (int y = outer.y; y < outer.br().y; ++y)
      for (int x = outer.x; x < outer.br().x; ++x)
        if (!inner.contains({x, y}))
          for (int c = 0; c < channels; ++c)
            ring[c].push_back(image.ptr<uchar>(y)[x * channels + c]);
    if (ring[0].empty()) continue;
    cv::Scalar paper;
    for (int c = 0; c < channels; ++c) paper[c] = Median(std::move(ring[c]));
    out(inner).setTo(paper);
  }
  return out;
}

// Reads `image` and measures its text. Tesseract's renderers write every
// word it read, a speck on bare paper or an i's dot on a line of its own
// read as '-', 'g' or ':' too: those are painted out and the page read
// again (18 of 4,399 words on the 15 bench pages were such specks).
PageReader::Page ReadWithoutSpecks(PageReader& reader, cv::Mat image, TextSize* size,
                                   size_t* erased, PageReader::Segmentation segmentation,
                                   cv::Mat* image_read) {
  PageReader::Page read = reader.Read(image, segmentation);
  *size = EstimateTextSize(read.words, read.lines);
  for (int pass = 0; pass < kSpeckPasses; ++pass) {
    const std::vector<cv::Rect> specks = SpeckBoxes(read.words, kSpeckSideEm * size->em_px);
    if (specks.empty()) break;
    image = WithoutSpecks(image, specks, std::max(2, int(std::ceil(kSpeckMarginEm * size->em_px))));
    *erased += specks.size();
    read = reader.Read(image, segmentation);
    *size = EstimateTextSize(read.words, read.lines);
  }
  *image_read = image;
  return read;
}

// What ReadPage read; Tesseract's renderers write the same reading.
struct PageReading {
  PageReader::Page page;         // words and lines in the pixels of the copy read
  double scale = 1;              // that copy's enlargement of the page
  TextSize size;                 // the text's, in the page's pixels
  size_t specks_erased = 0;      // before the reading kept
  std::string read_as = "auto";  // "auto", "single column" or "tinted shadows"
  double unread_print = 0;       // share of the print no word kept covers
  double unread_print_auto = 0;  // the same, of the first automatic reading's words
  bool without_ruling = false;   // read with the page's rules painted out
  bool print_stretched = false;  // read with its print stretched to black
  // What the kept reading was made from (specks erased): read again, it
  // gives the same words.
  cv::Mat image_read;
  PageReader::Segmentation segmentation = PageReader::Segmentation::kAuto;
  Rereading reread;  // doubted words read again (ReadPage)
  // The amounts given the page's decimal mark (ReadPage); its replacements
  // are the reread's and its own, the ones made in Tesseract's files.
  EvenedMarks marks;
};

// A page to read.
struct PageCopies {
  cv::Mat photo;  // as rendered: read again with tinted shadows divided out
  cv::Mat even;   // with the light's shading divided out
  // `even` with its table's rules painted out where it has some (at least
  // kMinRuleShare of its pixels), else empty.
  cv::Mat without_ruling;

  // The copy whose print a reading is measured against: print touching a
  // rule is no glyph-sized mark where the rule is.
  const cv::Mat& print() const { return without_ruling.empty() ? even : without_ruling; }
};

// The share of `page`'s print that none of `read`'s words (in the pixels of
// `page` enlarged by `scale`) covers.
double UnreadPrintOf(const cv::Mat& page, PageReader::Page read, double scale) {
  ScaleToPage(1 / scale, &read);
  return UnreadPrint(page, read.words);
}

// Whether a reading at mean word `confidence` leaving `unread` of the print
// unread is surer than one at (`than_confidence`, `than_unread`) by at least
// `min_gain` and leaves at most kMaxUnreadLossOfSurerReading more unread.
bool ReadsSurer(double confidence, double unread, double than_confidence, double than_unread,
                double min_gain) {
  return confidence >= than_confidence + min_gain &&
         unread <= than_unread + kMaxUnreadLossOfSurerReading;
}

// `size`, measured on the page enlarged by `scale`, in the page's pixels.
TextSize InPagePixels(TextSize size, double scale) {
  size.em_px /= scale;
  size.word_height_px /= scale;
  size.line_pitch_px /= scale;
  return size;
}

// Shading removal that takes a shadow of another tint than the lit paper
// (lit by the room, not the lamp: r09's greenish band) for paper too. Not
// the default: Tesseract then dropped r02's whole table.
ShadingOptions TintedShadows() {
  ShadingOptions o;
  o.max_chroma_distance = kTintedShadowChroma;
  return o;
}

// Reads `page.even` enlarged so that its long side has at least
// `min_long_side` pixels (0: as it is); where the page has rules and that
// leaves much print unread or is read with little confidence, also without
// them, and goes on with the copy without them where that leaves at least
// kMinUnreadGain less unread or is read with kMinConfidenceGainOfRules more
// confidence and no more than kMaxUnreadLossOfSurerReading more unread. Where
// the print is smaller there than kMinReadEmPx, the page is read again
// enlarged to kReadEmPx to the em. Where that leaves much print unread, it is
// read as one column, and as before from `page.photo` with tinted shadows
// divided out too; the reading that leaves the least unread is kept. The
// text's size is the one measured at the first enlargement (read larger,
// Tesseract boxes small print's words differently: set01's median word came
// out 60 % taller), or, where it measured none, the kept reading's. The kept
// reading is the last made: Tesseract's renderers write that one.
PageReading ReadBestCopy(PageReader& reader, const PageCopies& page, int min_long_side) {
  using Segmentation = PageReader::Segmentation;
  PageReading r;
  const bool ruled = !page.without_ruling.empty();
  const cv::Mat& print = page.print();
  const double long_side = std::max(page.even.cols, page.even.rows);
  r.scale = std::max(1.0, min_long_side / long_side);
  // Text size measured on the enlarged copy, where word boxes are not
  // rounded to a few pixels.
  cv::Mat copy = Enlarged(page.even, r.scale);
  r.page = ReadWithoutSpecks(reader, copy, &r.size, &r.specks_erased, Segmentation::kAuto,
                             &r.image_read);
  bool kept_read_last = true;
  const double unread_with_ruling = ruled ? UnreadPrintOf(print, r.page, r.scale) : 0;
  const double confidence_with_ruling = MeanConfidence(r.page.words);
  if (ruled && (unread_with_ruling > kMaxUnreadPrintOfRuledPage ||
                confidence_with_ruling < kMinConfidenceOfRuledPage)) {
    // Without its rules a table is read as one column: its rows come out as
    // lines. The automatic segmentation may cut it into a block per column
    // and give the cells in the wrong order.
    PageReading without;
    without.scale = r.scale;
    without.read_as = "single column";
    without.segmentation = Segmentation::kSingleColumn;
    const cv::Mat copy_without = Enlarged(page.without_ruling, r.scale);
    without.page = ReadWithoutSpecks(reader, copy_without, &without.size, &without.specks_erased,
                                     without.segmentation, &without.image_read);
    const double unread_without = UnreadPrintOf(print, without.page, r.scale);
    if (unread_without <= unread_with_ruling - kMinUnreadGain ||
        ReadsSurer(MeanConfidence(without.page.words), unread_without, confidence_with_ruling,
                   unread_with_ruling, kMinConfidenceGainOfRules)) {
      r = std::move(without);
      r.without_ruling = true;
      copy = copy_without;
    } else {
      kept_read_last = false;
    }
  }
  const cv::Mat& even = r.without_ruling ? page.without_ruling : page.even;
  r.size = InPagePixels(r.size, r.scale);
  if (min_long_side > 0 && r.size.em_px > 0 && r.size.em_px * r.scale < kMinReadEmPx) {
    const double again = std::min(kReadEmPx / r.size.em_px, kMaxReadLongSide / long_side);
    if (again > r.scale) {
      r.scale = again;
      r.specks_erased = 0;
      copy = Enlarged(even, r.scale);
      TextSize size_read_again;
      r.page = ReadWithoutSpecks(reader, copy, &size_read_again, &r.specks_erased, r.segmentation,
                                 &r.image_read);
      kept_read_last = true;
    }
  }

  r.unread_print = r.unread_print_auto = UnreadPrintOf(print, r.page, r.scale);
  if (r.unread_print <= kMaxUnreadPrint) {
    // The renderers write the reading last made.
    if (!kept_read_last) reader.Read(r.image_read, r.segmentation);
    return r;
  }
  const cv::Mat tinted = RemoveShading(page.photo, TintedShadows()).image;
  struct Alternative {
    std::string name;
    cv::Mat copy;
    Segmentation segmentation;
  };
  const std::vector<Alternative> alternatives = {
      {r.read_as, copy, r.segmentation},
      {"single column", copy, Segmentation::kSingleColumn},
      {"tinted shadows", Enlarged(r.without_ruling ? WithoutRuling(tinted).page : tinted, r.scale),
       Segmentation::kAuto}};
  size_t best = 0;
  double best_unread = r.unread_print;
  PageReader::Page read;
  TextSize size;
  size_t specks = 0;
  for (size_t i = 1; i < alternatives.size(); ++i) {
    // A page read without its rules was read as one column already.
    if (alternatives[i].name == alternatives[0].name) continue;
    specks = 0;
    read = ReadWithoutSpecks(reader, alternatives[i].copy, &size, &specks,
                             alternatives[i].segmentation, &r.image_read);
    const double unread = UnreadPrintOf(print, read, r.scale);
    if (unread <= r.unread_print - kMinUnreadGain && unread < best_unread)
      best = i, best_unread = unread;
  }
  const Alternative& kept = alternatives[best];
  if (best + 1 != alternatives.size()) {
    // Read once more: the renderers write the reading last made.
    specks = 0;
    read = ReadWithoutSpecks(reader, kept.copy, &size, &specks, kept.segmentation, &r.image_read);
  }
  r.page = std::move(read);
  r.specks_erased = specks;
  r.read_as = kept.name;
  r.segmentation = kept.segmentation;
  r.unread_print = best_unread;
  // A text size the first reading could not measure, from the kept one's
  // words at the same enlargement (a page is read larger only once its size
  // is known).
  if (r.size.em_px == 0 && size.em_px > 0) r.size = InPagePixels(size, r.scale);
  return r;
}

// The best of ReadBestCopy's readings; where Tesseract read it with a mean
// confidence below kMaxConfidenceToStretch, its copy is read again with the
// print stretched to black, and that reading kept (`reader` then holds it)
// where it is read with at least kMinConfidenceGain more and leaves at most
// kMaxUnreadLossOfSurerReading more print unread.
PageReading ReadKeptCopy(PageReader& reader, const PageCopies& page, int min_long_side) {
  PageReading r = ReadBestCopy(reader, page, min_long_side);
  const double confidence = MeanConfidence(r.page.words);
  if (r.page.words.empty() || confidence >= kMaxConfidenceToStretch) return r;
  // Read by another reader: `reader` keeps the reading for the renderers.
  PageReader stretched_reader(reader.language());
  TextSize size;
  size_t specks = 0;
  cv::Mat image_read;
  PageReader::Page read = ReadWithoutSpecks(stretched_reader, PrintStretchedToBlack(r.image_read),
                                            &size, &specks, r.segmentation, &image_read);
  const double unread = UnreadPrintOf(page.print(), read, r.scale);
  if (!ReadsSurer(MeanConfidence(read.words), unread, confidence, r.unread_print,
                  kMinConfidenceGain))
    return r;
  reader = std::move(stretched_reader);
  r.page = std::move(read);
  r.specks_erased += specks;
  r.image_read = image_read;
  r.unread_print = unread;
  r.print_stretched = true;
  return r;
}

// ReadKeptCopy's reading with the words Tesseract doubted read again on
// their own from the copy it read, and its amounts given the page's decimal
// mark (`reader` keeps Tesseract's reading: the replacements are made in its
// files after it writes them).
PageReading ReadPage(PageReader& reader, const PageCopies& page, int min_long_side,
                     const std::string& language) {
  PageReading r = ReadKeptCopy(reader, page, min_long_side);
  r.reread = RereadDoubtedWords(r.image_read, r.page.words, language);
  r.marks = EvenDecimalMarks(r.page.words, r.reread.replacements);
  r.page.words = WithReplacements(r.page.words, r.marks.replacements);
  return r;
}

struct Markup {
  std::string alto, hocr;
  bool words_replaced = true;  // in both
};

// Tesseract's ALTO and hOCR of the page read (page.xml, page.hocr in
// `staged`), naming the page image beside them rather than the staging
// folder it was read from (Tesseract writes the name escaped), with the
// words read again replaced as in the PDF (a file whose words are not the
// reading's keeps its own), mapped from the pixels of the enlarged copy read
// onto the page's.
Markup StagedMarkup(const fs::path& staged, const fs::path& image_path,
                    const std::string& image_name, const std::vector<WordReplacement>& replacements,
                    double ocr_scale, int read_ppi, int page_dpi) {
  const std::string staged_name = MarkupEscape(image_path.string());
  const std::string alto =
      ReplaceAll(ReadText(staged / "page.xml"), staged_name, MarkupEscape(image_name));
  const std::string hocr =
      ReplaceAll(ReadText(staged / "page.hocr"), staged_name, MarkupEscape(image_name));
  const std::optional<std::string> alto_replaced = ReplaceAltoWords(alto, replacements);
  const std::optional<std::string> hocr_replaced = ReplaceHocrWords(hocr, replacements);
  Markup m;
  m.alto = ScaleAltoPixels(alto_replaced.value_or(alto), 1 / ocr_scale);
  m.hocr = ScaleHocrPixels(hocr_replaced.value_or(hocr), 1 / ocr_scale, read_ppi, page_dpi);
  m.words_replaced = alto_replaced && hocr_replaced;
  return m;
}

Json WordsJson(const std::vector<Word>& words) {
  Json list = Json::array();
  for (const Word& w : words)
    list.push_back({w.box.x, w.box.y, w.box.width, w.box.height,
                    std::round(w.confidence * 1000) / 1000, w.text});
  return list;
}

}  // namespace

void DeclareOptions(OptionTable& table, PdfOptions* o) {
  table.Value("lang", &o->language,
              "Tesseract language(s) of the text layer, e.g. deu or eng+fra (each needs its "
              "Debian package tesseract-ocr-<lang>)");
  std::vector<std::pair<std::string, std::string>> formats = {{"auto", "auto"}, {"none", "none"}};
  for (const PaperFormat& f : PaperFormats()) formats.push_back({f.name, f.name});
  table.Choice("page-format", &o->page.format, formats,
               "paper size: auto (the format the page's aspect ratio matches within "
               "--format-tolerance, its member chosen by the print's size), none (the image "
               "at --dpi), or that format whatever the page's shape");
  table.Value("format-tolerance", &o->page.aspect_tolerance, 0.0, 0.2,
              "how far (fraction) the page's aspect ratio may be from a format's");
  table.Value("dpi", &o->page.dpi, 10.0, 2400.0,
              "image pixels per inch when the page matches no format and its print's size was "
              "not measured (else its body text is set at 10.5 pt), or with --page-format none");
  table.Choice("enhance", &o->enhance,
               {{"none", Enhance::kNone},
                {"even-light", Enhance::kEvenLight},
                {"black-white", Enhance::kBlackWhite}},
               "the page as a scanner gives it: none keeps the photo's colours, even-light "
               "divides the light's shading out (paper one even colour), black-white then "
               "makes print black on white (1 bit, smallest)");
  table.Value("jpeg-quality", &o->jpeg_quality, 1, 100, "quality of the embedded JPEG");
  table.Value("ocr-long-side", &o->ocr_min_long_side, 0, 20000,
              "OCR reads the page (its shading divided out) enlarged so that its long side has "
              "at least this many pixels (small print is read much better), and again enlarged "
              "to 30 px to the em where its print is still below 20 (0: read as it is); the text "
              "layer and ALTO boxes stay on the page's own pixels");
}

PdfInputs ReadPdfInputs(const fs::path& render_dir) {
  PdfInputs in;
  in.render_dir = render_dir;
  const fs::path json_path = render_dir / "render.json";
  const Json doc = ReadJsonFile(json_path);
  CheckFormat(doc, json_path, "docunfold.render", 1);
  const JsonReader render(doc, json_path);
  in.page = ReadImage(render_dir / "rectified.png");
  const int width = render.Integer("/width"), height = render.Integer("/height");
  if (width != in.page.cols || height != in.page.rows)
    throw InputError((render_dir / "rectified.png").string() + ": " + std::to_string(in.page.cols) +
                     "x" + std::to_string(in.page.rows) + " pixels, but render.json says " +
                     std::to_string(width) + "x" + std::to_string(height) +
                     " (rendered separately?)");
  in.shading_removed = doc.contains("shading") && doc["shading"].value("removed", false);
  return in;
}

PdfResult Run(const PdfOptions& o, const PdfInputs& in, const fs::path& out,
              const std::string& name, const Json& options_record) {
  StepTimer timer;
  PageReader reader(o.language);
  timer.Mark("load_language");

  const cv::Mat even_page = in.shading_removed ? in.page : RemoveShading(in.page).image;
  const cv::Mat shown = o.enhance == Enhance::kBlackWhite  ? BlackOnWhite(even_page)
                        : o.enhance == Enhance::kEvenLight ? even_page
                                                           : in.page;
  timer.Mark("enhance");

  PdfResult r;
  const Ruling ruling = WithoutRuling(even_page);
  PageReading read = ReadPage(
      reader, {in.page, even_page, ruling.rule_share >= kMinRuleShare ? ruling.page : cv::Mat()},
      o.ocr_min_long_side, o.language);
  const std::vector<WordReplacement>& replacements = read.marks.replacements;
  const double ocr_scale = read.scale;
  ScaleToPage(1 / ocr_scale, &read.page);
  r.words = std::move(read.page.words);
  r.text_size = read.size;
  r.specks_erased = read.specks_erased;
  for (const Word& w : r.words) r.mean_confidence += w.confidence / r.words.size();
  r.size = ChoosePageSize(in.page.cols, in.page.rows, r.text_size.em_px, o.page);
  timer.Mark("ocr");

  EnsureDirectory(out);
  Staging staging(out);
  const bool black_white = o.enhance == Enhance::kBlackWhite;
  const std::string image_name = name + (black_white ? ".tif" : ".jpg");
  const fs::path image_path = staging.dir() / image_name;
  const PageImage image = EncodePageImage(shown, black_white, o.jpeg_quality, image_path);
  const int ppi = std::max(1, int(std::lround(ocr_scale * (r.size.dpi_x + r.size.dpi_y) / 2)));
  reader.Write(staging.dir() / "page", image_path, ppi, name);
  const double width_pt = r.size.width_mm / kMillimetresPerInch * kPointsPerInch;
  const double height_pt = r.size.height_mm / kMillimetresPerInch * kPointsPerInch;
  const std::string tesseract = "Tesseract " + PageReader::Version();
  const FittedPage fitted = FitPage(
      staging.dir() / "page.pdf", staging.dir() / "fitted.pdf", width_pt, height_pt, image,
      {name, std::string("docunfold ") + ProgramVersion(), tesseract + ", qpdf " + QpdfVersion()},
      replacements);
  timer.Mark("write_pdf");

  const Markup markup = StagedMarkup(staging.dir(), image_path, image_name, replacements, ocr_scale,
                                     ppi, int(std::lround((r.size.dpi_x + r.size.dpi_y) / 2)));
  const bool replaced_in_every_file =
      markup.words_replaced && fitted.words_replaced == int(replacements.size());
  if (!replaced_in_every_file)
    Log("warning: the words replaced are not in every file (" +
        std::to_string(fitted.words_replaced) + " of " + std::to_string(replacements.size()) +
        " in the PDF)");
  Rename(image_path, out / image_name);
  WriteTextAtomic(out / (name + ".alto.xml"), markup.alto);
  WriteTextAtomic(out / (name + ".hocr"), markup.hocr);
  r.pdf_file = out / (name + ".pdf");
  r.pdf_bytes = fs::file_size(staging.dir() / "fitted.pdf");
  Rename(staging.dir() / "fitted.pdf", r.pdf_file);
  timer.Mark("write_files");

  Json& j = r.report;
  j = MakeHeader("docunfold.pdf", 1, "pdf", options_record);
  j["inputs"] = {{"render", in.render_dir.string()}};
  j["page"] = {{"format", r.size.format},
               {"rule", r.size.rule},
               {"width_mm", r.size.width_mm},
               {"height_mm", r.size.height_mm},
               {"width_pt", width_pt},
               {"height_pt", height_pt},
               {"page_aspect", r.size.page_aspect},
               {"aspect_error", r.size.aspect_error},
               {"text_pt", r.size.text_pt},
               {"dpi", {r.size.dpi_x, r.size.dpi_y}}};
  j["image"] = {{"file", image_name},
                {"width", in.page.cols},
                {"height", in.page.rows},
                {"encoding", black_white ? "ccitt-g4" : "jpeg"},
                {"bytes", image.data.size()},
                {"enhance", EnhanceName(o.enhance)},
                {"shading_removed_by_render", in.shading_removed}};
  if (!black_white) j["image"]["jpeg_quality"] = o.jpeg_quality;
  j["text"] = {{"engine", tesseract},
               {"language", o.language},
               {"read_from", "the page with the light's shading divided out"},
               {"read_scale", ocr_scale},
               {"read_as", read.read_as},
               {"ruling_share", ruling.rule_share},
               {"read_without_ruling", read.without_ruling},
               {"read_with_print_stretched", read.print_stretched},
               {"doubted_words_read_again", RereadingJson(read.reread, replaced_in_every_file)},
               {"decimal_marks", EvenedMarksJson(read.marks)},
               {"unread_print", read.unread_print},
               {"unread_print_auto", read.unread_print_auto},
               {"words", r.words.size()},
               {"mean_confidence", r.mean_confidence},
               {"specks_erased", r.specks_erased},
               {"size",
                {{"cue", r.text_size.cue},
                 {"em_px", r.text_size.em_px},
                 {"body_words", r.text_size.words},
                 {"word_height_px", r.text_size.word_height_px},
                 {"line_pitch_px", r.text_size.line_pitch_px}}}};
  j["files"] = {{"pdf", name + ".pdf"},
                {"pdf_bytes", r.pdf_bytes},
                {"alto", name + ".alto.xml"},
                {"hocr", name + ".hocr"},
                {"image", image_name}};
  j["words"] = WordsJson(r.words);
  Json timing = Json::object();
  for (const auto& [step, s] : timer.steps()) timing[step] = s;
  timing["total"] = timer.Total();
  j["timing_s"] = timing;
  WriteJsonAtomic(out / "pdf.json", j);
  return r;
}

}  // namespace docunfold::pdf
