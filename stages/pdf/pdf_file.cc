#include "stages/pdf/pdf_file.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <qpdf/QPDF.hh>
#include <qpdf/QPDFPageDocumentHelper.hh>
#include <qpdf/QPDFPageObjectHelper.hh>
#include <qpdf/QPDFWriter.hh>
#include <qpdf/QUtil.hh>
#include <stdexcept>
#include <vector>

namespace docunfold::pdf {
namespace {

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

// Tesseract's text layer shows each word with its trailing space, `w Tz
// [<word+space>] TJ`, stretched so that word and space together span the
// word's box: the glyphs stop one character short of its right edge, and a
// short word's gap to the next grows past an em, where pdftotext and viewers
// see a new column (r04's small print came out one word per line). This
// filter stretches the glyphs of the word alone over its box (the space,
// which readers do not box, goes past it), ending at least kWordGapEm before
// the next word on the line starts: readers join glyphs less than 0.1 em
// apart into one word ("Session3" where Tesseract's boxes of "Session" and
// "3" overlap). Positions are kept: Tesseract places every word with Td.
constexpr double kWordGapEm = 0.15;
// A gap wider than this between two words of one of Tesseract's lines is
// bridged by the glyphs of the word before it, to kWordGapEm before the
// next: readers take such a gap for a column's edge, and copy a receipt's
// item and its price, or a table's cells, a column at a time.
constexpr double kMaxWordGapEm = 1.0;
// Tesseract's glyph-less font draws every glyph half an em wide.
constexpr double kGlyphEm = 0.5;

// UTF-8 as the two-byte codes (UTF-16BE) Tesseract's glyph-less font shows.
std::string Utf16Codes(const std::string& utf8) {
  std::string out;
  auto put = [&out](unsigned unit) {
    out += char(unit >> 8);
    out += char(unit & 0xff);
  };
  for (size_t i = 0; i < utf8.size();) {
    const unsigned char c = utf8[i];
    const int extra = c < 0x80 ? 0 : c < 0xe0 ? 1 : c < 0xf0 ? 2 : 3;
    unsigned code = extra == 0 ? c : c & (0x3f >> extra);
    for (int k = 1; k <= extra && i + k < utf8.size(); ++k) code = code << 6 | (utf8[i + k] & 0x3f);
    i += extra + 1;
    if (code >= 0x10000) {
      put(0xd800 + ((code - 0x10000) >> 10));
      put(0xdc00 + ((code - 0x10000) & 0x3ff));
    } else {
      put(code);
    }
  }
  return out;
}

class WordGlyphsFillTheirBoxes : public QPDFObjectHandle::TokenFilter {
 public:
  explicit WordGlyphsFillTheirBoxes(const std::vector<WordReplacement>& replacements) {
    for (const WordReplacement& r : replacements) replacements_[r.in_files] = &r;
  }
  // Words whose text was replaced (where a word shown is not its
  // replacement's old text, none after it is).
  int replaced() const { return replaced_; }

  void handleToken(const QPDFTokenizer::Token& token) override {
    held_.push_back(token);
    switch (token.getType()) {
      case QPDFTokenizer::tt_integer:
      case QPDFTokenizer::tt_real:
        operands_.push_back({std::stod(token.getValue()), int(held_.size()) - 1});
        return;
      case QPDFTokenizer::tt_string:
        shown_ = token.getValue();
        shown_at_ = int(held_.size()) - 1;
        ++strings_;
        return;
      case QPDFTokenizer::tt_word:
        break;
      default:
        return;
    }
    const std::string& op = token.getValue();
    if (op == "Tf" && !operands_.empty()) font_size_ = operands_.back().value;
    if ((op == "TJ" || op == "Tj") && strings_ == 1) Replace(words_shown_++);
    if (codes_ > 0) {
      // The word shown waits for where the next one starts; the next one
      // dropped, its glyphs span their own box.
      const bool next_on_line =
          op == "Td" && operands_.size() == 2 && operands_[1].value == 0 && !Dropped(words_shown_);
      Stretch(next_on_line ? operands_[0].value : 0);
    } else if (op == "Tz" && operands_.size() == 1 && tz_at_ < 0) {
      tz_at_ = operands_[0].at;
      tz_ = operands_[0].value;
      Expect();
      return;  // held until the word is shown
    } else if (tz_at_ >= 0 && (op == "TJ" || op == "Tj") && strings_ == 1 && operands_.empty() &&
               shown_.size() % 2 == 0 && shown_.size() >= 4 &&
               shown_.compare(shown_.size() - 2, 2, std::string("\0 ", 2)) == 0) {
      codes_ = int(shown_.size() / 2);  // two bytes a glyph (Identity-H)
      Expect();
      return;
    }
    Flush();
  }
  void handleEOF() override { Flush(); }

 private:
  struct Operand {
    double value;
    int at;  // index in held_
  };

  bool Dropped(int word) const {
    const auto it = replacements_.find(word);
    return !misaligned_ && it != replacements_.end() && it->second->text.empty();
  }
  // The word shown (numbered `word`) given its replacement's text, its
  // glyphs as wide as the replacement says.
  void Replace(int word) {
    const auto it = replacements_.find(word);
    if (it == replacements_.end() || misaligned_) return;
    const WordReplacement& r = *it->second;
    const std::string space("\0 ", 2);
    const bool spaced = shown_.size() >= 2 && shown_.compare(shown_.size() - 2, 2, space) == 0;
    const std::string old = Utf16Codes(r.old_text) + (spaced ? space : "");
    if (old != shown_) {
      misaligned_ = true;
      return;
    }
    shown_ = r.text.empty() ? "" : Utf16Codes(r.text) + (spaced ? space : "");
    held_[shown_at_] = QPDFTokenizer::Token(QPDFTokenizer::tt_string, shown_);
    if (tz_at_ >= 0 && !shown_.empty()) {
      tz_ *= double(old.size()) / shown_.size() * r.width_ratio;
      held_[tz_at_] = QPDFTokenizer::Token(QPDFTokenizer::tt_real, Number(tz_));
    }
    ++replaced_;
  }

  // n codes span n * kGlyphEm * tz/100 em: the n - 1 of the word are
  // stretched over that, ending at least kWordGapEm before `next_start`
  // (text space units from the word's start; 0: none on the line), and
  // exactly that where the gap left would be wider than kMaxWordGapEm; never
  // narrower than Tesseract drew them.
  void Stretch(double next_start) {
    double stretch = tz_ * codes_ / (codes_ - 1);
    if (next_start > 0 && font_size_ > 0) {
      const double next_em = next_start / font_size_;
      const double to_next = 100 * (next_em - kWordGapEm) / (kGlyphEm * (codes_ - 1));
      const double gap_em = next_em - kGlyphEm * (codes_ - 1) * stretch / 100;
      stretch = gap_em > kMaxWordGapEm ? to_next : std::min(stretch, to_next);
    }
    held_[tz_at_] = QPDFTokenizer::Token(QPDFTokenizer::tt_real, Number(std::max(tz_, stretch)));
  }
  void Expect() {
    operands_.clear();
    strings_ = 0;
  }
  void Flush() {
    for (const QPDFTokenizer::Token& t : held_) writeToken(t);
    held_.clear();
    Expect();
    tz_at_ = -1;
    codes_ = 0;
  }

  std::vector<QPDFTokenizer::Token> held_;              // since the last operator written
  std::vector<Operand> operands_;                       // since the last operator
  int strings_ = 0;                                     // strings since the last operator
  std::string shown_;                                   // the last of them
  double font_size_ = 0;                                // the last Tf's
  int tz_at_ = -1;                                      // a held Tz operand's index, or -1
  double tz_ = 100;                                     // its value
  int codes_ = 0;                                       // glyphs of a word shown, held
  int shown_at_ = -1;                                   // the last string's index in held_
  std::map<int, const WordReplacement*> replacements_;  // by word
  int words_shown_ = 0;
  int replaced_ = 0;
  bool misaligned_ = false;
};

}  // namespace

QPDFObjectHandle ImageObject(QPDF* pdf, const PageImage& image) {
  QPDFObjectHandle stream = QPDFObjectHandle::newStream(pdf);
  const bool jpeg = image.encoding == PageImage::Encoding::kJpeg;
  QPDFObjectHandle parms = QPDFObjectHandle::newNull();
  if (!jpeg) {
    parms = QPDFObjectHandle::newDictionary();
    parms.replaceKey("/K", QPDFObjectHandle::newInteger(-1));
    parms.replaceKey("/Columns", QPDFObjectHandle::newInteger(image.width));
    parms.replaceKey("/Rows", QPDFObjectHandle::newInteger(image.height));
  }
  stream.replaceStreamData(
      image.data, QPDFObjectHandle::newName(jpeg ? "/DCTDecode" : "/CCITTFaxDecode"), parms);
  QPDFObjectHandle dict = stream.getDict();
  dict.replaceKey("/Type", QPDFObjectHandle::newName("/XObject"));
  dict.replaceKey("/Subtype", QPDFObjectHandle::newName("/Image"));
  dict.replaceKey("/Width", QPDFObjectHandle::newInteger(image.width));
  dict.replaceKey("/Height", QPDFObjectHandle::newInteger(image.height));
  dict.replaceKey("/ColorSpace", QPDFObjectHandle::newName(jpeg ? "/DeviceRGB" : "/DeviceGray"));
  dict.replaceKey("/BitsPerComponent", QPDFObjectHandle::newInteger(jpeg ? 8 : 1));
  return stream;
}

FittedPage FitPage(const fs::path& in, const fs::path& out, double width_pt, double height_pt,
                   const PageImage& image, const DocumentInfo& info,
                   const std::vector<WordReplacement>& replacements) {
  QPDF pdf;
  pdf.setSuppressWarnings(true);
  try {
    pdf.processFile(in.c_str());
    std::vector<QPDFPageObjectHelper> pages = QPDFPageDocumentHelper(pdf).getAllPages();
    if (pages.size() != 1)
      throw std::runtime_error(in.string() + ": expected one page, found " +
                               std::to_string(pages.size()));
    QPDFPageObjectHelper& page = pages.front();
    const QPDFObjectHandle::Rectangle box = page.getMediaBox().getArrayAsRectangle();
    FittedPage fitted;
    fitted.width_pt = width_pt;
    fitted.height_pt = height_pt;
    fitted.scale_x = width_pt / (box.urx - box.llx);
    fitted.scale_y = height_pt / (box.ury - box.lly);
    // Everything the renderer drew (image and text layer) goes through one
    // transform onto the new page.
    page.addPageContents(
        QPDFObjectHandle::newStream(&pdf, "q " + Number(fitted.scale_x) + " 0 0 " +
                                              Number(fitted.scale_y) + " " +
                                              Number(-box.llx * fitted.scale_x) + " " +
                                              Number(-box.lly * fitted.scale_y) + " cm\n"),
        true);
    page.addPageContents(QPDFObjectHandle::newStream(&pdf, "\nQ\n"), false);
    // The image first, under the (invisible) text.
    QPDFObjectHandle resources = page.getObjectHandle().getKey("/Resources");
    if (!resources.isDictionary()) {
      resources = QPDFObjectHandle::newDictionary();
      page.getObjectHandle().replaceKey("/Resources", resources);
    }
    QPDFObjectHandle xobjects = resources.getKey("/XObject");
    if (!xobjects.isDictionary()) {
      xobjects = QPDFObjectHandle::newDictionary();
      resources.replaceKey("/XObject", xobjects);
    }
    xobjects.replaceKey("/PageImage", ImageObject(&pdf, image));
    page.addPageContents(
        QPDFObjectHandle::newStream(&pdf, "q " + Number(width_pt) + " 0 0 " + Number(height_pt) +
                                              " 0 0 cm /PageImage Do Q\n"),
        true);
    page.getObjectHandle().replaceKey(
        "/MediaBox",
        QPDFObjectHandle::newFromRectangle(QPDFObjectHandle::Rectangle(0, 0, width_pt, height_pt)));
    const auto words = std::make_shared<WordGlyphsFillTheirBoxes>(replacements);
    page.addContentTokenFilter(words);

    QPDFObjectHandle dict = QPDFObjectHandle::newDictionary();
    dict.replaceKey("/Title", QPDFObjectHandle::newUnicodeString(info.title));
    dict.replaceKey("/Creator", QPDFObjectHandle::newUnicodeString(info.creator));
    dict.replaceKey("/Producer", QPDFObjectHandle::newUnicodeString(info.producer));
    pdf.getTrailer().replaceKey("/Info", pdf.makeIndirectObject(dict));

    QPDFWriter writer(pdf, out.c_str());
    writer.setDeterministicID(true);
    writer.setObjectStreamMode(qpdf_o_generate);
    writer.setCompressStreams(true);
    writer.write();
    fitted.words_replaced = words->replaced();
    return fitted;
  } catch (const std::runtime_error&) {
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("qpdf: ") + e.what());
  }
}

std::string QpdfVersion() { return QPDF::QPDFVersion(); }

}  // namespace docunfold::pdf
