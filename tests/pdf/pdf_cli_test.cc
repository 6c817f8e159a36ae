// The pdf program on pages made from ground truth (a replacement render
// writing the same files): the PDF at its paper size, its text layer and
// ALTO file against independent tools, the size of a 300 dpi page, the
// enhancements, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/json_io.h"
#include "tests/pdf/pdf_checks.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

// A render folder as the render stage leaves it: rectified.png and the
// render.json fields the pdf stage reads.
fs::path WriteRenderDir(const fs::path& work, const cv::Mat& page) {
  const fs::path dir = work / "60_render";
  fs::create_directories(dir);
  cv::imwrite((dir / "rectified.png").string(), page);
  std::ofstream(dir / "render.json") << Json{
      {"format", "docunfold.render"},
      {"version", 1},
      {"width", page.cols},
      {"height", page.rows}}.dump();
  return dir;
}

class PdfCli : public ::testing::Test {
 protected:
  // set06's true flat page (A4 at 150 dpi), read once by the pdf program.
  static void SetUpTestSuite() {
    shared_ = std::make_unique<TempDir>();
    page_ = cv::imread((SampleDir("set06") / "ground_truth/flat.png").string());
    render_ = WriteRenderDir(shared_->path() / "letter", page_);
    run_ = std::make_unique<CommandResult>(Pdf(render_, shared_->path() / "letter/80_pdf"));
  }
  static void TearDownTestSuite() {
    run_.reset();
    shared_.reset();
  }

  static CommandResult Pdf(const fs::path& render, const fs::path& out,
                           const std::string& flags = "") {
    return RunCommand(Quote(StageBinary("pdf").string()) + " --render " + Quote(render.string()) +
                      " --out " + Quote(out.string()) + " " + flags);
  }
  static fs::path Out() { return shared_->path() / "letter/80_pdf"; }

  TempDir dir_;
  static std::unique_ptr<TempDir> shared_;
  static cv::Mat page_;
  static fs::path render_;
  static std::unique_ptr<CommandResult> run_;
};

std::unique_ptr<TempDir> PdfCli::shared_;
cv::Mat PdfCli::page_;
fs::path PdfCli::render_;
std::unique_ptr<CommandResult> PdfCli::run_;

TEST_F(PdfCli, WritesTheFilesNamedAfterTheWorkDirectory) {
  ASSERT_EQ(run_->exit_code, 0) << run_->output;
  EXPECT_NE(run_->output.find("pdf: wrote"), std::string::npos) << run_->output;
  for (const char* f : {"letter.pdf", "letter.alto.xml", "letter.hocr", "letter.jpg", "pdf.json"})
    EXPECT_TRUE(fs::is_regular_file(Out() / f)) << f;
  // Nothing else: the staging folder is gone.
  EXPECT_EQ(std::distance(fs::directory_iterator(Out()), fs::directory_iterator()), 5);
  const CommandResult v = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                                     Quote((Out() / "pdf.json").string()));
  EXPECT_EQ(v.exit_code, 0) << v.output;
  const Json report = ReadJsonFile(Out() / "pdf.json");
  EXPECT_EQ(report["page"]["format"], "a4");
  EXPECT_NEAR(report["page"]["dpi"][0].get<double>(), 150, 0.5);
  EXPECT_GT(report["text"]["words"].get<int>(), 150);
  EXPECT_EQ(report["words"].size(), report["text"]["words"].get<size_t>());
}

TEST_F(PdfCli, PageIsA4ForPdfinfoAndPassesQpdfCheck) {
  ASSERT_EQ(run_->exit_code, 0) << run_->output;
  const std::vector<PdfPage> pages = PdfPages(Out() / "letter.pdf");
  ASSERT_EQ(pages.size(), 1u);
  EXPECT_NEAR(pages[0].width_pt, 210 / 25.4 * 72, 0.01);
  EXPECT_NEAR(pages[0].height_pt, 297 / 25.4 * 72, 0.01);
  std::string check;
  EXPECT_TRUE(QpdfCheckPasses(Out() / "letter.pdf", &check)) << check;
}

TEST_F(PdfCli, TextLayerReadsAsWellAsTesseractOnTheImage) {
  ASSERT_EQ(run_->exit_code, 0) << run_->output;
  const std::string truth = ReadFileText(SampleDir("set06") / "ground_truth/text.txt");
  const double pdf_cer = CharacterErrorRate(truth, PdfText(Out() / "letter.pdf"));
  const double image_cer = CharacterErrorRate(truth, TesseractText(render_ / "rectified.png"));
  EXPECT_LE(pdf_cer, image_cer + 0.02) << "pdftotext " << pdf_cer << ", image " << image_cer;
}

// evaluate --pdf reads the PDF back as these tests do: the same words found
// as pdftotext -layout gives, the page's true size, and a text that follows
// set06's lines (CER 0.001 in the bench's run of the pipeline).
TEST_F(PdfCli, EvaluateMeasuresItsTextLayerAndSize) {
  ASSERT_EQ(run_->exit_code, 0) << run_->output;
  const fs::path out = dir_ / "70_eval/pdf.json";
  const CommandResult r = RunCommand(
      Quote(StageBinary("evaluate").string()) + " --pdf " + Quote((Out() / "letter.pdf").string()) +
      " --data " + Quote(SampleDir("set06").string()) + " --out " + Quote(out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pdf: words found"), std::string::npos) << r.output;
  const CommandResult v = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                                     Quote(out.string()));
  EXPECT_EQ(v.exit_code, 0) << v.output;
  const Json doc = ReadJsonFile(out);
  EXPECT_EQ(doc["format"], "docunfold.pdf-metrics");
  EXPECT_EQ(doc["pages"], 1);
  const std::string truth = ReadFileText(SampleDir("set06") / "ground_truth/text.txt");
  const double found = doc["text"]["words_found"].get<double>();
  EXPECT_NEAR(found, WordsFound(truth, PdfText(Out() / "letter.pdf")), 0.01);
  EXPECT_GE(found, 0.95);
  EXPECT_LE(doc["text"]["cer_reading_order"].get<double>(), 0.05);
  EXPECT_LT(doc["page"]["size_error"].get<double>(), 0.001);
  EXPECT_NEAR(doc["page"]["width_mm"].get<double>(), 210, 0.1);
}

// What a viewer highlights for a word found or selected is the word's print:
// each word of the text layer spans the box Tesseract read it in (its
// ALTO box), not, as Tesseract's renderer writes it, that box less one
// character's width (a word of n letters stretched as n + 1 with its space).
// A word the next on its line stands further than an em from reaches to just
// before it instead (a table's cells), so that readers keep the line whole.
TEST_F(PdfCli, EachWordOfTheTextLayerSpansItsPrint) {
  ASSERT_EQ(run_->exit_code, 0) << run_->output;
  const std::vector<AltoWord> alto = AltoWords(Out() / "letter.alto.xml");
  const std::vector<PdfWord> words = PdfWords(Out() / "letter.pdf");
  const double pt_per_px = 210 / 25.4 * 72 / page_.cols;
  int paired = 0, spanning = 0, bridging = 0;
  for (const PdfWord& w : words) {
    size_t same = alto.size();
    for (size_t i = 0; i < alto.size(); ++i) {
      const AltoWord& a = alto[i];
      const double dx = std::abs(a.box.x * pt_per_px - w.box.x);
      const double dy = std::abs((a.box.y + a.box.height) * pt_per_px - w.box.br().y);
      if (a.text == w.text && dx < 5 && dy < 5 &&
          (same == alto.size() || dx < std::abs(alto[same].box.x * pt_per_px - w.box.x)))
        same = i;
    }
    if (same == alto.size()) continue;
    ++paired;
    const AltoWord& a = alto[same];
    const double ratio = w.box.width / (a.box.width * pt_per_px);
    if (ratio > 0.9 && ratio < 1.1) {
      ++spanning;
    } else if (ratio >= 1.1 && same + 1 < alto.size() && alto[same + 1].line == a.line) {
      const cv::Rect& next = alto[same + 1].box;
      const bool wide_gap = next.x - a.box.br().x > a.box.height;
      if (wide_gap && w.box.br().x <= next.x * pt_per_px + 0.5) ++bridging;
    }
  }
  RecordProperty("words_spanning_their_box",
                 std::to_string(spanning) + "/" + std::to_string(paired));
  RecordProperty("words_bridging_a_gap", std::to_string(bridging) + "/" + std::to_string(paired));
  ASSERT_GT(paired, 150) << words.size() << " words in the text layer, " << alto.size()
                         << " in ALTO";
  EXPECT_GE(spanning + bridging, 0.95 * paired)
      << spanning << " of " << paired << " words span their box, " << bridging << " bridge a gap";
  EXPECT_GE(spanning, 0.6 * paired);
  EXPECT_GT(bridging, 0);
}

TEST_F(PdfCli, RenderedBackTheImageIsThePage) {
  ASSERT_EQ(run_->exit_code, 0) << run_->output;
  const cv::Mat back = RenderPdfPage(Out() / "letter.pdf", 1, page_.size());
  ASSERT_EQ(back.size(), page_.size());
  EXPECT_GE(MsSsimOf(page_, back), 0.99);
}

TEST_F(PdfCli, AltoIsValidAndItsWordsLieOnPrint) {
  ASSERT_EQ(run_->exit_code, 0) << run_->output;
  const fs::path alto = Out() / "letter.alto.xml";
  EXPECT_EQ(AltoSchemaErrors(alto), "");
  EXPECT_NE(ReadFileText(alto).find("<fileName>letter.jpg</fileName>"), std::string::npos);
  const std::vector<AltoWord> words = AltoWords(alto);
  ASSERT_GT(words.size(), 150u);
  const cv::Mat image = cv::imread((Out() / "letter.jpg").string());
  ASSERT_EQ(image.size(), page_.size());
  const std::vector<AltoWord> light = WordsWithoutPrint(image, words);
  EXPECT_TRUE(light.empty()) << light.size() << " words without print, e.g. '" << light[0].text
                             << "'";
}

TEST_F(PdfCli, A300DpiA4PageInColourFitsInOneAndAHalfMegabytes) {
  // synth's page at 300 dpi with a photo's sensor noise: a 2480 x 3508 page.
  const CommandResult synth =
      RunCommand(Quote(StageBinary("synth").string()) + " --out " + Quote((dir_ / "set").string()) +
                 " --flat-dpi 300 --views 2 --seed 7");
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  cv::Mat page = cv::imread((dir_ / "set/ground_truth/flat.png").string());
  cv::Mat noise(page.size(), CV_16SC3);
  cv::randn(noise, 0, 3);
  page.convertTo(page, CV_16SC3);
  cv::add(page, noise, page);
  page.convertTo(page, CV_8UC3);
  const CommandResult r = Pdf(WriteRenderDir(dir_ / "page300", page), dir_ / "out");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json report = ReadJsonFile(dir_ / "out/pdf.json");
  EXPECT_EQ(report["page"]["format"], "a4");
  EXPECT_NEAR(report["page"]["dpi"][1].get<double>(), 300, 1);
  EXPECT_LE(fs::file_size(dir_ / "out/page300.pdf"), 1500u * 1000u);
}

// The lower half of the letter in a shadow lit by the room, greener than the
// lamp's light on the upper half: the shading removal takes the shadow for
// print, Tesseract reads 59 words of the page's upper half (a search finds
// 26 % of them), and the page is read again with the tinted shadow divided
// out too (all 249).
TEST_F(PdfCli, LinesUnderATintedShadowAreRead) {
  cv::Mat page;
  page_.convertTo(page, CV_32FC3);
  cv::Mat shadow = page.rowRange(page.rows / 2, page.rows);
  cv::multiply(shadow, cv::Scalar(0.55, 0.60, 0.52), shadow);
  page.convertTo(page, CV_8UC3);
  const CommandResult r = Pdf(WriteRenderDir(dir_ / "shadow", page), dir_ / "out");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json report = ReadJsonFile(dir_ / "out/pdf.json");
  EXPECT_EQ(report["text"]["read_as"], "tinted shadows");
  EXPECT_GT(report["text"]["unread_print_auto"].get<double>(), 0.3);
  EXPECT_LT(report["text"]["unread_print"].get<double>(), 0.05);
  EXPECT_GE(WordsFound(ReadFileText(SampleDir("set06") / "ground_truth/text.txt"),
                       PdfText(dir_ / "out/shadow.pdf")),
            0.95);
}

TEST_F(PdfCli, BlackWhiteEmbedsOneBitPrint) {
  const CommandResult r = Pdf(render_, dir_ / "out", "--enhance black-white --name bw");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CommandResult images =
      RunCommand("pdfimages -list " + Quote((dir_ / "out/bw.pdf").string()));
  EXPECT_NE(images.output.find("ccitt"), std::string::npos) << images.output;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "out/bw.tif"));
  EXPECT_LT(fs::file_size(dir_ / "out/bw.pdf"), fs::file_size(Out() / "letter.pdf"));
  EXPECT_EQ(AltoSchemaErrors(dir_ / "out/bw.alto.xml"), "");
}

TEST_F(PdfCli, PageFormatNoneTakesTheImageAtTheGivenDpi) {
  const CommandResult r = Pdf(render_, dir_ / "out", "--page-format none --dpi 100");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<PdfPage> pages = PdfPages(dir_ / "out/letter.pdf");
  ASSERT_EQ(pages.size(), 1u);
  EXPECT_NEAR(pages[0].width_pt, page_.cols / 100.0 * 72, 0.01);
  EXPECT_NEAR(pages[0].height_pt, page_.rows / 100.0 * 72, 0.01);
}

// A letter rendered a little blurred: Tesseract boxes its words 0.83 of a
// line pitch high, which taken for 0.75 em would make its 10 pt print 15 pt
// on A4, and the page A5. The lines' pitch keeps it A4.
TEST_F(PdfCli, ABlurredLetterIsStillA4) {
  const CommandResult made =
      RunCommand(Quote(StageBinary("synth").string()) + " --seed 5102 --kind text --creases 0 " +
                 "--views 1 --width 320 --height 240 --out " + Quote((dir_ / "data").string()));
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const cv::Mat flat = cv::imread((dir_ / "data/ground_truth/flat.png").string());
  ASSERT_FALSE(flat.empty());
  cv::Mat page;
  cv::resize(flat, page, cv::Size(900, int(std::lround(flat.rows * 900.0 / flat.cols))), 0, 0,
             cv::INTER_AREA);
  cv::GaussianBlur(page, page, cv::Size(), 0.8);
  const fs::path render = WriteRenderDir(dir_ / "blurred", page);
  const CommandResult r = Pdf(render, dir_ / "blurred/80_pdf");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json report = ReadJsonFile(dir_ / "blurred/80_pdf/pdf.json");
  EXPECT_EQ(report["page"]["format"], "a4") << report["text"]["size"].dump();
  EXPECT_NEAR(report["page"]["text_pt"].get<double>(), 10.5, 1.5);
}

TEST_F(PdfCli, NoRenderedPageIsBadInput) {
  const CommandResult r = Pdf(dir_ / "nothing", dir_ / "out");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("render.json"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(PdfCli, ARenderJsonOfAnotherImageIsBadInput) {
  const fs::path render = WriteRenderDir(dir_ / "w", page_);
  cv::imwrite((render / "rectified.png").string(), cv::Mat(100, 80, CV_8UC3, cv::Scalar::all(255)));
  const CommandResult r = Pdf(render, dir_ / "out");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("rectified.png"), std::string::npos) << r.output;
}

TEST_F(PdfCli, AMissingLanguageNamesItsPackageAndLeavesTheOldPdf) {
  fs::copy(Out(), dir_ / "out");
  const std::string before = ReadFileText(dir_ / "out/letter.pdf");
  const CommandResult r = Pdf(render_, dir_ / "out", "--lang xyz --name letter");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("tesseract-ocr-xyz"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_EQ(ReadFileText(dir_ / "out/letter.pdf"), before);
}

TEST_F(PdfCli, AnUnwritableFolderExitsFour) {
  std::ofstream(dir_ / "file") << "x";
  const CommandResult r = Pdf(render_, dir_ / "file/out");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("file/out"), std::string::npos) << r.output;
}

TEST_F(PdfCli, BadFlagsAreUsageErrors) {
  EXPECT_EQ(Pdf(render_, dir_ / "out", "--page-format b5").exit_code, 2);
  EXPECT_EQ(Pdf(render_, dir_ / "out", "--jpeg-quality 0").exit_code, 2);
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(PdfCli, HelpListsEveryOption) {
  const CommandResult r = RunCommand(Quote(StageBinary("pdf").string()) + " --help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* flag :
       {"--render", "--out", "--name", "--lang", "--page-format", "--format-tolerance", "--dpi",
        "--enhance", "--jpeg-quality", "--ocr-long-side"})
    EXPECT_NE(r.output.find(flag), std::string::npos) << flag;
}

TEST_F(PdfCli, ABookStopsAtAFailedPageNamingIt) {
  const CommandResult r = RunCommand(
      "make -s -f " + Quote((SourceDir() / "pipeline.mk").string()) +
      " NO_BUILD=1 BUILD=" + Quote(StageBinary("pdf").parent_path().parent_path().string()) +
      " WORK_ROOT=" + Quote(dir_.path().string()) +
      " book BOOK=letter DATASETS='no-such-set set01' 2>&1");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("page no-such-set failed"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "letter.pdf"));
  EXPECT_FALSE(fs::exists(dir_ / "set01"));
}

}  // namespace
}  // namespace docunfold::testing
