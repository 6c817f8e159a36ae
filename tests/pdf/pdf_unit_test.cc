// The pdf stage's pure parts: paper size from shape and print size, the
// print's size from what Tesseract read, how much print no word covers, a
// table's rules taken out of the copy read, ALTO and hOCR mapped back onto
// the page's pixels, doubted words read again and replaced in ALTO and hOCR,
// a page's amounts given one decimal mark.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "common/errors.h"
#include "stages/pdf/contrast.h"
#include "stages/pdf/decimal_marks.h"
#include "stages/pdf/markup_scale.h"
#include "stages/pdf/page_size.h"
#include "stages/pdf/ruling.h"
#include "stages/pdf/text_size.h"
#include "stages/pdf/unread_print.h"
#include "stages/pdf/word_reread.h"

namespace docunfold::pdf {
namespace {

// Pixels to the em of `pt`-point text on a page `long_mm` long drawn
// `long_px` pixels long.
double EmPx(double pt, double long_px, double long_mm) {
  return pt * kMillimetresPerInch / kPointsPerInch * long_px / long_mm;
}

TEST(PageSize, IsoShapeWithBodyTextIsA4) {
  const PageSize s = ChoosePageSize(1240, 1754, EmPx(10, 1754, 297), {});
  EXPECT_EQ(s.format, "a4");
  EXPECT_DOUBLE_EQ(s.width_mm, 210);
  EXPECT_DOUBLE_EQ(s.height_mm, 297);
  EXPECT_NEAR(s.dpi_x, 150, 0.1);
  EXPECT_NEAR(s.text_pt, 10, 1e-9);
  EXPECT_EQ(s.rule, "aspect ratio and text size");
}

TEST(PageSize, LandscapeKeepsItsOrientation) {
  const PageSize s = ChoosePageSize(1754, 1240, 0, {});
  EXPECT_EQ(s.format, "a4");
  EXPECT_DOUBLE_EQ(s.width_mm, 297);
  EXPECT_DOUBLE_EQ(s.height_mm, 210);
}

TEST(PageSize, PrintSizeNamesTheIsoMember) {
  // A4 unless the text would be smaller than 7.6 pt or larger than 14.5 pt
  // there: 11 pt print on an A5 page (15.6 pt on A4) is A5, 10 pt (14.1 pt
  // on A4) is taken for A4, the more common paper.
  EXPECT_EQ(ChoosePageSize(1240, 1754, EmPx(11, 1754, 210), {}).format, "a5");
  EXPECT_EQ(ChoosePageSize(1240, 1754, EmPx(10, 1754, 210), {}).format, "a4");
  EXPECT_EQ(ChoosePageSize(1240, 1754, EmPx(10, 1754, 420), {}).format, "a3");
  EXPECT_EQ(ChoosePageSize(1240, 1754, EmPx(10, 1754, 148), {}).format, "a6");
}

TEST(PageSize, WithoutTextTheMostCommonMember) {
  const PageSize s = ChoosePageSize(1240, 1754, 0, {});
  EXPECT_EQ(s.format, "a4");
  EXPECT_EQ(s.text_pt, 0);
  EXPECT_NE(s.rule.find("no text"), std::string::npos);
}

TEST(PageSize, LetterAndLegal) {
  EXPECT_EQ(ChoosePageSize(1275, 1650, 0, {}).format, "letter");
  EXPECT_EQ(ChoosePageSize(1275, 2100, 0, {}).format, "legal");
}

TEST(PageSize, AspectWithinTheTolerance) {
  // 1.5 % longer than A4's ratio: still A4, exactly; 2.5 %: no format.
  const PageSize close = ChoosePageSize(1000, int(1000 * 1.41429 * 1.014), 0, {});
  EXPECT_EQ(close.format, "a4");
  EXPECT_NEAR(close.aspect_error, 0.014, 0.001);
  EXPECT_DOUBLE_EQ(close.height_mm, 297);
  const PageSize off = ChoosePageSize(1000, int(1000 * 1.41429 * 1.025), 0, {});
  EXPECT_EQ(off.format, "none");
  EXPECT_EQ(off.rule, "dpi");
  EXPECT_NEAR(off.dpi_x, 300, 1e-9);
  EXPECT_NEAR(off.width_mm, 1000 / 300.0 * 25.4, 1e-9);
}

TEST(PageSize, NoFormatsShapeTakesItsSizeFromItsPrint) {
  // An A4 page with its top third cut off, 10.5 pt print at 150 dpi.
  const PageSize cut = ChoosePageSize(1240, 1170, EmPx(10.5, 1240, 210), {});
  EXPECT_EQ(cut.format, "none");
  EXPECT_EQ(cut.rule, "text size");
  EXPECT_NEAR(cut.width_mm, 210, 0.01);
  EXPECT_NEAR(cut.height_mm, 210 * 1170.0 / 1240, 0.01);
  EXPECT_NEAR(cut.dpi_y, 1240 / (210 / 25.4), 0.01);
  EXPECT_EQ(cut.text_pt, 10.5);
}

TEST(PageSize, ReceiptsKeepTheirLengthAtTheRollWidth) {
  // 80 x 200 mm at 5 px/mm with 8.5 pt print: the 80 mm roll.
  const PageSize s = ChoosePageSize(400, 1000, EmPx(8.5, 400, 80), {});
  EXPECT_EQ(s.format, "receipt-80");
  EXPECT_DOUBLE_EQ(s.width_mm, 80);
  EXPECT_DOUBLE_EQ(s.height_mm, 200);
  EXPECT_EQ(s.aspect_error, 0);
  // On a 58 mm roll the same pixels are finer: 10 pt print there would be
  // 13.8 pt on an 80 mm roll (8.5 pt there, 11.7 pt, is taken for 80 mm).
  EXPECT_EQ(ChoosePageSize(400, 1000, EmPx(10, 400, 58), {}).format, "receipt-58");
  EXPECT_EQ(ChoosePageSize(400, 1000, EmPx(8.5, 400, 58), {}).format, "receipt-80");
  EXPECT_EQ(ChoosePageSize(400, 1000, 0, {}).format, "receipt-80");
}

TEST(PageSize, GivenFormatOrDpi) {
  PageSizeOptions o;
  o.format = "letter";
  const PageSize letter = ChoosePageSize(1240, 1754, 0, o);
  EXPECT_EQ(letter.format, "letter");
  EXPECT_EQ(letter.rule, "given");
  EXPECT_GT(letter.aspect_error, 0.05);
  o.format = "none";
  o.dpi = 100;
  const PageSize none = ChoosePageSize(1240, 1754, EmPx(10, 1754, 297), o);
  EXPECT_EQ(none.format, "none");
  EXPECT_NEAR(none.width_mm, 12.4 * 25.4, 1e-9);
  EXPECT_NEAR(none.dpi_y, 100, 1e-9);
  o.format = "b5";
  EXPECT_THROW(ChoosePageSize(1240, 1754, 0, o), UsageError);
}

std::vector<Word> BodyWords(int n, int height) {
  std::vector<Word> words;
  for (int i = 0; i < n; ++i) words.push_back({cv::Rect(10 * i, 0, 40, height), 0.95, "word"});
  return words;
}

std::vector<TextLine> Lines(int n, double pitch) {
  std::vector<TextLine> lines;
  for (int i = 0; i < n; ++i)
    lines.push_back(
        {0, cv::Rect(100, int(i * pitch), 800, 20), {100, i * pitch + 15}, {900, i * pitch + 16}});
  return lines;
}

TEST(TextSize, FromWordHeights) {
  const TextSize s = EstimateTextSize(BodyWords(30, 24), Lines(10, 48));
  EXPECT_EQ(s.cue, "word height");
  EXPECT_DOUBLE_EQ(s.em_px, 24 / 0.75);
  EXPECT_EQ(s.words, 30u);
  EXPECT_NEAR(s.line_pitch_px, 48, 1e-9);
}

TEST(TextSize, TheSmallerOfTheTwoCuesWins) {
  // Blurred print: words boxed 24 px high on lines 30 px apart say 32 px to
  // the em, the lines 22.2.
  const TextSize s = EstimateTextSize(BodyWords(30, 24), Lines(10, 30));
  EXPECT_EQ(s.cue, "line pitch (below the word height's)");
  EXPECT_NEAR(s.em_px, 30 / 1.35, 1e-9);
  EXPECT_NEAR(s.word_height_px, 24, 1e-9);
}

TEST(TextSize, FromLinePitchWhenWordBoxesSpanLines) {
  const TextSize s = EstimateTextSize(BodyWords(30, 28), Lines(10, 16));
  EXPECT_EQ(s.cue, "line pitch");
  EXPECT_NEAR(s.em_px, 16 / 1.35, 1e-9);
}

TEST(TextSize, WordsBoxedTallerThanTheirLinesAreApartAreLeftOut) {
  // A table of 10 rows 48 px apart with 25 words 24 px high, and a paragraph
  // of 4 lines 16 px apart whose 30 words Tesseract boxed 28 px high: the
  // paragraph's words say nothing of the text's height, though the median
  // over all words and lines would take them.
  std::vector<TextLine> lines = Lines(10, 48);
  for (TextLine& l : Lines(4, 16)) {
    l.block = 1;
    l.box.y += 500;
    l.baseline_start.y += 500;
    l.baseline_end.y += 500;
    lines.push_back(l);
  }
  std::vector<Word> words = BodyWords(25, 24);
  for (size_t i = 0; i < words.size(); ++i) words[i].line = int(i % 10);
  for (Word w : BodyWords(30, 28)) {
    w.line = 10 + int(words.size() % 4);
    words.push_back(w);
  }
  const TextSize s = EstimateTextSize(words, lines);
  EXPECT_EQ(s.cue, "word height");
  EXPECT_DOUBLE_EQ(s.em_px, 24 / 0.75);
  EXPECT_EQ(s.words, 55u);
  // Too few words left within their lines: the line pitch.
  words.erase(words.begin(), words.begin() + 10);
  EXPECT_EQ(EstimateTextSize(words, lines).cue, "line pitch");
}

TEST(TextSize, NotMeasuredFromFewOrDoubtfulWords) {
  EXPECT_EQ(EstimateTextSize(BodyWords(10, 24), Lines(10, 40)).em_px, 0);
  std::vector<Word> doubtful = BodyWords(30, 24);
  for (Word& w : doubtful) w.confidence = 0.5;
  EXPECT_EQ(EstimateTextSize(doubtful, {}).em_px, 0);
  std::vector<Word> numbers = BodyWords(30, 24);
  for (Word& w : numbers) w.text = "12.50";
  EXPECT_EQ(EstimateTextSize(numbers, {}).em_px, 0);
}

TEST(TextSize, LinesOfDifferentBlocksOrColumnsAreNotNeighbours) {
  std::vector<TextLine> lines = Lines(10, 16);
  for (size_t i = 0; i < lines.size(); ++i) lines[i].block = int(i);
  EXPECT_EQ(EstimateTextSize(BodyWords(30, 10), lines).line_pitch_px, 0);
  lines = Lines(10, 16);
  for (size_t i = 1; i < lines.size(); i += 2) lines[i].box.x += 2000;
  EXPECT_EQ(EstimateTextSize(BodyWords(30, 10), lines).line_pitch_px, 0);
}

TEST(TextSize, SpecksAreWordsSmallerThanAQuarterEmEveryWay) {
  // At 12 px to the em: specks Tesseract read on bare paper go; a hyphen
  // (4 x 1 px), a short word and an upright bar stay.
  const std::vector<Word> words = {{cv::Rect(5, 5, 1, 1), 0.85, "-"},
                                   {cv::Rect(9, 9, 2, 2), 0.6, "g"},
                                   {cv::Rect(20, 5, 4, 1), 0.9, "-"},
                                   {cv::Rect(30, 5, 15, 7), 0.95, "an"},
                                   {cv::Rect(50, 2, 1, 9), 0.7, "|"}};
  const std::vector<cv::Rect> specks = SpeckBoxes(words, 0.25 * 12);
  ASSERT_EQ(specks.size(), 2u);
  EXPECT_EQ(specks[0], cv::Rect(5, 5, 1, 1));
  EXPECT_EQ(specks[1], cv::Rect(9, 9, 2, 2));
  EXPECT_TRUE(SpeckBoxes(words, 0).empty());
}

// A receipt's two columns, items on the left and prices on the right, under
// a shadow across its lower half and a frame round the page.
TEST(UnreadPrint, TheShareOfPrintNoWordCovers) {
  cv::Mat page(600, 400, CV_8UC3, cv::Scalar(235, 235, 235));
  page(cv::Rect(0, 300, 400, 300)) *= 0.55;
  cv::rectangle(page, cv::Rect(20, 20, 360, 560), cv::Scalar(40, 40, 40), 2);
  std::vector<Word> items, prices;
  for (int row = 0; row < 10; ++row) {
    const int y = 60 + row * 50;
    cv::putText(page, "Butter", {40, y}, cv::FONT_HERSHEY_SIMPLEX, 0.8, cv::Scalar(20, 20, 20), 2);
    cv::putText(page, "15.54", {260, y}, cv::FONT_HERSHEY_SIMPLEX, 0.8, cv::Scalar(20, 20, 20), 2);
    items.push_back({cv::Rect(36, y - 22, 104, 30), 0.9, "Butter"});
    prices.push_back({cv::Rect(256, y - 22, 84, 30), 0.9, "15.54"});
  }
  std::vector<Word> both = items;
  both.insert(both.end(), prices.begin(), prices.end());
  EXPECT_LT(UnreadPrint(page, both), 0.02);
  const double without_prices = UnreadPrint(page, items);
  EXPECT_GT(without_prices, 0.3);
  EXPECT_LT(without_prices, 0.6);
  EXPECT_GT(UnreadPrint(page, {}), 0.98);
  // A word of whitespace boxed over the whole page covers nothing.
  std::vector<Word> blank = items;
  blank.push_back({cv::Rect(0, 0, 400, 600), 0.95, " "});
  EXPECT_NEAR(UnreadPrint(page, blank), without_prices, 1e-9);
  EXPECT_EQ(UnreadPrint(cv::Mat(600, 400, CV_8UC3, cv::Scalar(235, 235, 235)), {}), 0);
}

// Dark pixels (below 128 in every channel) of `page` within `box`.
int DarkPixels(const cv::Mat& page, const cv::Rect& box) {
  cv::Mat grey;
  cv::cvtColor(page(box), grey, cv::COLOR_BGR2GRAY);
  return cv::countNonZero(grey < 128);
}

TEST(Ruling, ATablesRulesArePaintedOutAndItsPrintKept) {
  // A statement's table: 12 rows of 4 cells, ruled, half of it in shadow,
  // words touching the rules under them; above it a heading and a line of
  // small print whose letters touch.
  cv::Mat page(900, 640, CV_8UC3, cv::Scalar(232, 236, 238));
  page(cv::Rect(0, 525, 640, 375)) *= 0.6;
  const std::vector<int> columns = {40, 140, 380, 500, 600};
  const cv::Scalar ink(30, 30, 30);
  std::vector<cv::Rect> words;
  for (int row = 0; row <= 12; ++row)
    cv::line(page, {columns.front(), 200 + row * 50}, {columns.back(), 200 + row * 50}, ink, 2);
  for (int x : columns) cv::line(page, {x, 200}, {x, 800}, ink, 1);
  for (int row = 0; row < 12; ++row)
    for (size_t c = 0; c + 1 < columns.size(); ++c) {
      const cv::Point at(columns[c] + 8, 200 + row * 50 + 49);  // on the rule below
      cv::putText(page, c == 1 ? "Refund GARAGE" : "12.34", at, cv::FONT_HERSHEY_SIMPLEX, 0.7, ink,
                  2);
      words.push_back(cv::Rect(at.x, at.y - 18, c == 1 ? 200 : 70, 14));  // above the rule
    }
  cv::putText(page, "ACCOUNT STATEMENT", {40, 80}, cv::FONT_HERSHEY_DUPLEX, 1.2, ink, 3);
  cv::putText(page, "permission to use a particular library", {40, 140}, cv::FONT_HERSHEY_PLAIN,
              0.9, ink, 2);
  const cv::Rect heading(30, 40, 600, 110);

  const Ruling r = WithoutRuling(page);
  // 13 rules across and 5 down, each grown to about 5 and 3 pixels.
  EXPECT_GT(r.rule_share, 0.06);
  EXPECT_LT(r.rule_share, 0.09);
  // No rule is left, in the light or in the shadow...
  for (int row = 0; row <= 12; ++row)
    EXPECT_EQ(DarkPixels(r.page, cv::Rect(300, 199 + row * 50, 60, 3)), 0) << "row " << row;
  for (int x : columns) EXPECT_EQ(DarkPixels(r.page, cv::Rect(x - 1, 300, 3, 400)), 0) << x;
  // ... and the print is as it was.
  for (const cv::Rect& w : words) EXPECT_EQ(DarkPixels(r.page, w), DarkPixels(page, w)) << w;
  EXPECT_EQ(DarkPixels(r.page, heading), DarkPixels(page, heading));

  // A page without rules is the page itself.
  const cv::Mat text_only = page(heading).clone();
  const Ruling none = WithoutRuling(text_only);
  EXPECT_EQ(none.rule_share, 0);
  EXPECT_EQ(none.page.data, text_only.data);

  // A grey page keeps its one channel; a page of a few pixels has no rules.
  cv::Mat grey(200, 300, CV_8UC1, cv::Scalar(230));
  cv::line(grey, {20, 100}, {280, 100}, cv::Scalar(20), 2);
  const Ruling grey_ruling = WithoutRuling(grey);
  EXPECT_EQ(grey_ruling.page.type(), CV_8UC1);
  EXPECT_EQ(cv::countNonZero(grey_ruling.page < 128), 0);
  EXPECT_EQ(WithoutRuling(cv::Mat(3, 3, CV_8UC3, cv::Scalar::all(200))).rule_share, 0);
}

TEST(Contrast, PalePrintIsStretchedToBlackOnWhite) {
  // A receipt's pale, thin print (grey 150 on paper at 234) on a page
  // lighter at the top than at the foot.
  cv::Mat page(400, 300, CV_8UC3, cv::Scalar(234, 234, 234));
  page(cv::Rect(0, 300, 300, 100)).setTo(cv::Scalar(226, 226, 226));
  for (int row = 0; row < 8; ++row)
    cv::putText(page, "Butter 13.52", {20, 40 + row * 45}, cv::FONT_HERSHEY_PLAIN, 1.4,
                cv::Scalar(150, 150, 150), 1);
  const cv::Mat out = PrintStretchedToBlack(page);
  ASSERT_EQ(out.type(), CV_8UC1);
  ASSERT_EQ(out.size(), page.size());
  double darkest = 0, lightest = 0;
  cv::minMaxLoc(out, &darkest, &lightest);
  EXPECT_LE(darkest, 10);
  EXPECT_EQ(lightest, 255);
  EXPECT_EQ(out.at<uchar>(150, 290), 255);  // the paper, white
  EXPECT_GE(out.at<uchar>(350, 290), 200);  // the paper in the foot's light, nearly so

  // A page with a single short word: black is the word's, not the paper's
  // grain; a page without print is left as it was, in grey.
  cv::Mat sparse(600, 600, CV_8UC1, cv::Scalar(230));
  cv::randu(sparse, cv::Scalar(226), cv::Scalar(235));
  cv::putText(sparse, "OK", {280, 300}, cv::FONT_HERSHEY_PLAIN, 1, cv::Scalar(120), 1);
  const cv::Mat stretched = PrintStretchedToBlack(sparse);
  EXPECT_GE(stretched.at<uchar>(100, 100), 180) << "the paper's grain made print";
  cv::minMaxLoc(stretched, &darkest, &lightest);
  EXPECT_LE(darkest, 10);
  const cv::Mat blank(100, 100, CV_8UC3, cv::Scalar(200, 210, 220));
  cv::Mat blank_grey;
  cv::cvtColor(blank, blank_grey, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::norm(PrintStretchedToBlack(blank), blank_grey, cv::NORM_INF), 0);
  EXPECT_TRUE(PrintStretchedToBlack(cv::Mat()).empty());
}

TEST(MarkupScale, AltoPositionsAndSizes) {
  const std::string alto =
      R"(<Page WIDTH="2000" HEIGHT="3000" PHYSICAL_IMG_NR="0" ID="page_0">)"
      R"(<String ID="string_3" HPOS="101" VPOS="40" WIDTH="60" HEIGHT="21" WC="0.96" CONTENT="WIDTH"/>)";
  EXPECT_EQ(
      ScaleAltoPixels(alto, 0.5),
      R"(<Page WIDTH="1000" HEIGHT="1500" PHYSICAL_IMG_NR="0" ID="page_0">)"
      R"(<String ID="string_3" HPOS="50" VPOS="20" WIDTH="30" HEIGHT="11" WC="0.96" CONTENT="WIDTH"/>)");
  EXPECT_EQ(ScaleAltoPixels(alto, 1), alto);
}

TEST(MarkupScale, HocrBoxesBaselinesAndResolution) {
  const std::string hocr =
      "title='image \"p.jpg\"; bbox 0 0 2000 3000; ppageno 0; scan_res 600 600'>"
      "title=\"bbox 100 40 900 62; baseline 0.002 -6; x_size 22; x_descenders 5.5; x_ascenders 6\""
      "title='bbox 100 40 160 61; x_wconf 96'";
  EXPECT_EQ(ScaleHocrPixels(hocr, 0.5, 600, 300),
            "title='image \"p.jpg\"; bbox 0 0 1000 1500; ppageno 0; scan_res 300 300'>"
            "title=\"bbox 50 20 450 31; baseline 0.002 -3; x_size 11.0000; x_descenders "
            "2.7500; x_ascenders 3.0000\""
            "title='bbox 50 20 80 31; x_wconf 96'");
  // A mark 1 pixel wide read at 3x keeps a pixel.
  EXPECT_EQ(ScaleAltoPixels(R"(HPOS="301" WIDTH="1")", 1.0 / 3), R"(HPOS="100" WIDTH="1")");
}

// Words of a receipt's line as Tesseract reads pale prices: "Yoghurt" sure,
// its price cut into three doubted pieces, then a doubted word on the next
// line and one past a wide gap.
std::vector<Word> ReceiptLine() {
  return {
      {cv::Rect(50, 500, 90, 20), 0.95, "Yoghurt", 0}, {cv::Rect(604, 499, 36, 16), 0.37, "BPX", 0},
      {cv::Rect(641, 497, 7, 24), 0.25, "Be", 0},      {cv::Rect(650, 497, 6, 24), 0.29, "|", 0},
      {cv::Rect(50, 530, 60, 20), 0.40, "Pasla", 1},   {cv::Rect(400, 530, 60, 20), 0.50, "ns", 1},
      {cv::Rect(480, 530, 20, 20), 0.99, " ", 1},      {cv::Rect(510, 530, 20, 20), 0.10, " ", 1}};
}

TEST(WordReread, DoubtedWordsAreGroupedAlongTheirLine) {
  const std::vector<std::vector<int>> groups = DoubtedWordGroups(ReceiptLine());
  // The price's pieces together; the next line's words apart (344 px is
  // more than two word heights); blank words never.
  EXPECT_EQ(groups, (std::vector<std::vector<int>>{{1, 2, 3}, {4}, {5}}));
  RereadOptions sure;
  sure.max_confidence = 0.2;
  EXPECT_TRUE(DoubtedWordGroups(ReceiptLine(), sure).empty());
  EXPECT_TRUE(IsBlank(" \t") && IsBlank("") && !IsBlank(" a"));
}

TEST(WordReread, PalePriceIsReadAgainInBlackAndWhite) {
  // A price in pale, thin print (grey 160 on paper at 232) and a word
  // Tesseract read surely are given as read wrongly: the doubted one is read
  // again and replaced, over the box of its print; the sure one is kept.
  cv::Mat page(120, 700, CV_8UC3, cv::Scalar(232, 232, 232));
  cv::putText(page, "13.52", {420, 70}, cv::FONT_HERSHEY_SIMPLEX, 1.2, cv::Scalar(160, 160, 160), 2,
              cv::LINE_AA);
  cv::putText(page, "Butter", {40, 70}, cv::FONT_HERSHEY_SIMPLEX, 1.2, cv::Scalar(160, 160, 160), 2,
              cv::LINE_AA);
  const std::vector<Word> words = {{cv::Rect(40, 40, 130, 32), 0.9, "Buttor", 0},
                                   {cv::Rect(420, 40, 110, 32), 0.22, "13502", 0}};
  const Rereading reread = RereadDoubtedWords(page, words, "eng");
  EXPECT_EQ(reread.groups, 1);
  ASSERT_EQ(reread.replacements.size(), 1u);
  const WordReplacement& r = reread.replacements[0];
  EXPECT_EQ(r.word, 1);
  EXPECT_EQ(r.in_files, 1);
  EXPECT_EQ(r.old_text, "13502");
  EXPECT_EQ(r.text, "13.52");
  EXPECT_GE(r.confidence, 0.85);
  EXPECT_EQ(r.box & cv::Rect(415, 35, 120, 42), r.box) << r.box;
  EXPECT_GE(r.box.width, 90);
  const std::vector<Word> replaced = WithReplacements(words, reread.replacements);
  ASSERT_EQ(replaced.size(), 2u);
  EXPECT_EQ(replaced[0].text, "Buttor");
  EXPECT_EQ(replaced[1].text, "13.52");
}

// Tesseract's files after a doubted price, read as three words, was read
// again as one: the first word takes it over the group's box, the others go.
std::vector<WordReplacement> PriceReadAgain() {
  return {{1, 1, "BPX", "7.37", 0.94, cv::Rect(604, 498, 52, 18), 1.4},
          {2, 2, "Be", "", 0, {}, 1},
          {3, 3, "|", "", 0, {}, 1}};
}

TEST(WordReread, AltoWordsReplacedAndDropped) {
  const std::string alto =
      R"(<TextLine><String ID="string_0" HPOS="50" VPOS="500" WIDTH="90" HEIGHT="20" WC="0.95" CONTENT="Yoghurt"/>)"
      R"(<SP WIDTH="10" VPOS="500" HPOS="140"/><String ID="string_1" HPOS="604" VPOS="499" WIDTH="36" HEIGHT="16" WC="0.37" CONTENT="BPX"/>)"
      R"(<SP WIDTH="1" VPOS="500" HPOS="640"/><String ID="string_2" HPOS="641" VPOS="497" WIDTH="7" HEIGHT="24" WC="0.25" CONTENT="Be"/>)"
      R"(<SP WIDTH="2" VPOS="500" HPOS="648"/><String ID="string_3" HPOS="650" VPOS="497" WIDTH="6" HEIGHT="24" WC="0.29" CONTENT="|"/></TextLine>)";
  EXPECT_EQ(
      ReplaceAltoWords(alto, PriceReadAgain()).value_or("misaligned"),
      R"(<TextLine><String ID="string_0" HPOS="50" VPOS="500" WIDTH="90" HEIGHT="20" WC="0.95" CONTENT="Yoghurt"/>)"
      R"(<SP WIDTH="10" VPOS="500" HPOS="140"/><String ID="string_1" HPOS="604" VPOS="498" WIDTH="52" HEIGHT="18" WC="0.94" CONTENT="7.37"/></TextLine>)");
  EXPECT_EQ(ReplaceAltoWords(alto, {}).value_or(""), alto);
  // A file whose words are not the reading's (another reading, or fewer
  // words) is left for the caller to keep as it is.
  std::vector<WordReplacement> shifted = PriceReadAgain();
  for (WordReplacement& r : shifted) ++r.in_files;
  EXPECT_FALSE(ReplaceAltoWords(alto, shifted).has_value());
}

TEST(WordReread, HocrWordsReplacedAndDropped) {
  const std::string hocr =
      "<span class='ocr_line' id='line_1_1'>\n"
      "     <span class='ocrx_word' id='word_1_1' title='bbox 50 500 140 520; x_wconf "
      "95'>Yoghurt</span>\n"
      "     <span class='ocrx_word' id='word_1_2' title='bbox 604 499 640 515; x_wconf "
      "37'>BPX</span>\n"
      "     <span class='ocrx_word' id='word_1_3' title='bbox 641 497 648 521; x_wconf "
      "25'>Be</span>\n"
      "     <span class='ocrx_word' id='word_1_4' title='bbox 650 497 656 521; x_wconf "
      "29'>|</span>\n"
      "    </span>";
  EXPECT_EQ(ReplaceHocrWords(hocr, PriceReadAgain()).value_or("misaligned"),
            "<span class='ocr_line' id='line_1_1'>\n"
            "     <span class='ocrx_word' id='word_1_1' title='bbox 50 500 140 520; x_wconf "
            "95'>Yoghurt</span>\n"
            "     <span class='ocrx_word' id='word_1_2' title='bbox 604 498 656 516; x_wconf "
            "94'>7.37</span>\n"
            "    </span>");
  std::vector<WordReplacement> other = PriceReadAgain();
  other[0].old_text = "B&X";
  EXPECT_FALSE(ReplaceHocrWords(hocr, other).has_value());
}

// Words of a receipt as read, one word to a line: `texts` in order.
std::vector<Word> WordsOf(const std::vector<std::string>& texts) {
  std::vector<Word> words;
  for (size_t i = 0; i < texts.size(); ++i)
    words.push_back({cv::Rect(300, 20 * int(i), 60, 16), 0.9, texts[i], int(i)});
  return words;
}

TEST(DecimalMarks, AmountsReadWithACommaTakeThePagesFullStop) {
  const std::vector<Word> words = WordsOf({"Pasta", "14,66", "2.90", " ", "5.47", "$12.45", "-3.20",
                                           "975", "1,234", "12,5", "2624", "0.83", "7.10", "3.33"});
  // Read again before: "975" as "9,75" (it is evened too, its old text kept)
  // and "2624" as "2.21".
  const std::vector<WordReplacement> prior = {
      {7, 6, "975", "9,75", 0.93, cv::Rect(300, 140, 50, 16), 1.2},
      {10, 9, "2624", "2.21", 0.95, cv::Rect(300, 200, 60, 16), 1}};
  const EvenedMarks e = EvenDecimalMarks(words, prior);
  EXPECT_EQ(e.mark, ".");
  EXPECT_EQ(e.amounts, 10);  // not "1,234" (a thousands mark) nor "12,5"
  ASSERT_EQ(e.evened.size(), 2u);
  EXPECT_EQ(e.evened[0].word, 1);
  EXPECT_EQ(e.evened[0].before, "14,66");
  EXPECT_EQ(e.evened[0].after, "14.66");
  EXPECT_EQ(e.evened[1].word, 7);
  EXPECT_EQ(e.evened[1].before, "9,75");
  ASSERT_EQ(e.replacements.size(), 3u);
  const WordReplacement& fresh = e.replacements[0];
  EXPECT_EQ(fresh.word, 1);
  EXPECT_EQ(fresh.in_files, 1);
  EXPECT_EQ(fresh.old_text, "14,66");
  EXPECT_EQ(fresh.text, "14.66");
  EXPECT_EQ(fresh.box, words[1].box);
  EXPECT_DOUBLE_EQ(fresh.width_ratio, 1);
  // The word read again keeps its new box and Tesseract's text as the old.
  EXPECT_EQ(e.replacements[1].old_text, "975");
  EXPECT_EQ(e.replacements[1].text, "9.75");
  EXPECT_EQ(e.replacements[1].in_files, 6);  // the blank word is not in the files
  EXPECT_DOUBLE_EQ(e.replacements[1].width_ratio, 1.2);
  EXPECT_EQ(e.replacements[2].text, "2.21");
  const std::vector<Word> read = WithReplacements(words, e.replacements);
  EXPECT_EQ(read[1].text, "14.66");
  EXPECT_EQ(read[8].text, "1,234");
}

TEST(DecimalMarks, APageWrittenWithCommasKeepsThem) {
  const EvenedMarks e =
      EvenDecimalMarks(WordsOf({"1,20", "3,45", "12,00", "4.50", "0,99", "7,10"}), {});
  EXPECT_EQ(e.mark, ",");
  ASSERT_EQ(e.replacements.size(), 1u);
  EXPECT_EQ(e.replacements[0].text, "4,50");
}

TEST(DecimalMarks, FewOrMixedAmountsAreLeftAlone) {
  // Four amounts are too few to tell the page's mark by.
  EXPECT_TRUE(EvenDecimalMarks(WordsOf({"1.20", "3.45", "12.00", "4,50"}), {}).mark.empty());
  // Seven of ten is too close a split.
  const std::vector<WordReplacement> prior = {{0, 0, "1.20", "1.26", 0.9, {}, 1}};
  const EvenedMarks mixed = EvenDecimalMarks(
      WordsOf({"1.20", "3.45", "12.00", "4,50", "5.00", "6,10", "7.77", "8.80", "9,90", "2.00"}),
      prior);
  EXPECT_TRUE(mixed.mark.empty());
  EXPECT_EQ(mixed.amounts, 10);
  EXPECT_TRUE(mixed.evened.empty());
  ASSERT_EQ(mixed.replacements.size(), 1u);
  EXPECT_EQ(mixed.replacements[0].text, "1.26");
  EXPECT_TRUE(EvenDecimalMarks({}, {}).replacements.empty());
}

}  // namespace
}  // namespace docunfold::pdf
