// The evaluate and baseline programs as a user runs them: outputs, the
// documented exit codes and messages, and nothing written on failure.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/json_io.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

const char* kLines[] = {"The quick brown fox jumps over", "the lazy dog near the river",
                        "Pack my box with five dozen", "liquor jugs before noon"};

// A data set whose ground truth is a printed page of 880 x 680 pixels: that
// is exactly the evaluation area, so the flow runs at 440 x 340.
fs::path MakeDataSet(const fs::path& root) {
  fs::create_directories(root / "ground_truth");
  fs::create_directories(root / "images");
  cv::Mat3b page(680, 880, cv::Vec3b(245, 245, 240));
  std::ofstream text(root / "ground_truth" / "text.txt");
  for (int i = 0; i < 4; ++i) {
    cv::putText(page, kLines[i], cv::Point(40, 110 + 140 * i), cv::FONT_HERSHEY_SIMPLEX, 1.4,
                cv::Scalar(20, 20, 20), 3, cv::LINE_AA);
    text << kLines[i] << "\n";
  }
  // Some texture so that the flow has something to hold on to everywhere.
  cv::RNG rng(3);
  for (int i = 0; i < 400; ++i)
    cv::circle(page, cv::Point(rng.uniform(0, 880), rng.uniform(0, 680)), rng.uniform(2, 6),
               cv::Scalar::all(rng.uniform(150, 230)), cv::FILLED);
  cv::imwrite((root / "ground_truth" / "flat.png").string(), page);
  return root;
}

std::string Evaluate(const std::string& args) {
  return Quote(StageBinary("evaluate").string()) + " " + args;
}

class EvaluateCli : public ::testing::Test {
 protected:
  TempDir dir;
  fs::path data = MakeDataSet(dir / "set");
  fs::path flat = data / "ground_truth" / "flat.png";
  fs::path out = dir / "work" / "70_eval" / "metrics.json";
  std::string Args(const fs::path& result, const std::string& extra = "") const {
    return "--data " + Quote(data.string()) + " --work " + Quote((dir / "work").string()) +
           " --result " + Quote(result.string()) + " --out " + Quote(out.string()) + " " + extra;
  }
  // flat.png moved by the affine map `result_from_truth` (pixels), written as `name`.
  fs::path WriteMovedPage(const cv::Matx23d& result_from_truth, const std::string& name) const {
    const cv::Mat page = cv::imread(flat.string());
    cv::Mat moved;
    cv::warpAffine(page, moved, cv::Mat(result_from_truth), page.size(), cv::INTER_LINEAR,
                   cv::BORDER_REPLICATE);
    const fs::path path = dir / name;
    cv::imwrite(path.string(), moved);
    return path;
  }
};

TEST_F(EvaluateCli, IdenticalImageScoresPerfectlyAndValidates) {
  CommandResult r = RunCommand(Evaluate(Args(flat, "--method self")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json m = ReadJsonFile(out);
  EXPECT_EQ(m["format"], "docunfold.metrics");
  EXPECT_EQ(m["method"], "self");
  EXPECT_NEAR(m["metrics"]["ms_ssim"].get<double>(), 1.0, 1e-12);
  EXPECT_LT(m["metrics"]["ld"].get<double>(), 0.05);
  EXPECT_LT(m["metrics"]["li_d"].get<double>(), 0.05);
  ASSERT_TRUE(m["metrics"]["cer"].is_number()) << m["ocr"].dump();
  EXPECT_EQ(m["metrics"]["cer"].get<double>(), 0.0);
  EXPECT_EQ(m["metrics"]["ed"].get<int>(), 0);
  EXPECT_EQ(m["metrics"]["wer"].get<double>(), 0.0);
  EXPECT_GT(m["ocr"]["reference_chars"].get<int>(), 40) << "OCR read almost nothing";
  // The printed text is read back from the flat page with few errors.
  ASSERT_TRUE(m["metrics"]["cer_text"].is_number());
  EXPECT_LT(m["metrics"]["cer_text"].get<double>(), 0.2);
  EXPECT_EQ(m["geometry"]["skipped"], "no mesh3d.ply in 50_optimize/ or 40_init/");
  EXPECT_EQ(m["ocr"]["reference_from_cache"], false);
  EXPECT_NE(r.output.find("MS-SSIM 1.0000"), std::string::npos) << r.output;

  CommandResult v = RunCommand(Quote((SourceDir() / "scripts" / "validate-json").string()) + " " +
                               Quote(out.string()));
  EXPECT_EQ(v.exit_code, 0) << v.output;

  // A second row of the same data set reads the ground truth's OCR text from
  // the cache and gets the same figures.
  r = RunCommand(Evaluate(Args(flat, "--no-flow")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json again = ReadJsonFile(out);
  EXPECT_EQ(again["ocr"]["reference_from_cache"], true);
  EXPECT_EQ(again["metrics"]["cer"], m["metrics"]["cer"]);
  EXPECT_EQ(again["ocr"]["reference_chars"], m["ocr"]["reference_chars"]);
}

TEST_F(EvaluateCli, ShiftOfSixPixelsIsThreeAtTheFlowResolution) {
  const fs::path shifted = WriteMovedPage(cv::Matx23d(1, 0, 6, 0, 1, 0), "shifted.png");
  CommandResult r = RunCommand(Evaluate(Args(shifted, "--no-ocr")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json j = ReadJsonFile(out);
  EXPECT_NEAR(j["metrics"]["ld"].get<double>(), 3.0, 0.3);
  EXPECT_LT(j["metrics"]["ms_ssim"].get<double>(), 0.9);
  EXPECT_TRUE(j["metrics"]["cer"].is_null());
  EXPECT_EQ(j["ocr"]["skipped"], "--no-ocr");
  EXPECT_EQ(j["producer"]["options"]["ocr"], false);
  EXPECT_EQ(j["producer"]["options"]["flow"], true);
  EXPECT_EQ(j["flow"]["size"], Json::array({440, 340}));
}

TEST_F(EvaluateCli, RegisteredUndoesAShiftAndStretchButNotTheLiteratureFigure) {
  // The page moved 6 px right and stretched 1 % down: one affine map.
  const fs::path moved = WriteMovedPage(cv::Matx23d(1, 0, 6, 0, 1.01, 0), "moved.png");
  CommandResult r = RunCommand(Evaluate(Args(moved, "--no-ocr --registered")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json j = ReadJsonFile(out);
  EXPECT_LT(j["metrics"]["ms_ssim"].get<double>(), 0.9);
  EXPECT_GT(j["metrics"]["ms_ssim_registered"].get<double>(), 0.97) << j["registration"].dump();
  const Json& a = j["registration"]["result_from_truth"];  // in fractions of the page
  EXPECT_NEAR(a[0][0].get<double>(), 1.0, 2e-3);
  EXPECT_NEAR(a[1][1].get<double>(), 1.01, 2e-3);
  EXPECT_NEAR(a[0][2].get<double>(), 6.0 / 880, 1e-3);
  EXPECT_NE(r.output.find("registered by one affine map"), std::string::npos) << r.output;
  CommandResult v = RunCommand(Quote((SourceDir() / "scripts" / "validate-json").string()) + " " +
                               Quote(out.string()));
  EXPECT_EQ(v.exit_code, 0) << v.output;

  // Without the flag the figure is null and the block says why.
  r = RunCommand(Evaluate(Args(moved, "--no-ocr")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(ReadJsonFile(out)["metrics"]["ms_ssim_registered"].is_null());
  EXPECT_EQ(ReadJsonFile(out)["registration"]["skipped"], "no --registered");
}

TEST_F(EvaluateCli, OcrAtTruthSizeResizesTheResultFirst) {
  // The page rendered at twice the size: OCRed at flat.png's size it reads
  // as the ground truth does.
  cv::Mat page = cv::imread(flat.string()), big;
  cv::resize(page, big, cv::Size(), 2, 2, cv::INTER_CUBIC);
  cv::imwrite((dir / "big.png").string(), big);
  CommandResult r = RunCommand(Evaluate(Args(dir / "big.png", "--no-flow --ocr-at-truth-size")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json j = ReadJsonFile(out);
  EXPECT_EQ(j["ocr"]["result_ocr_size"], Json::array({880, 680}));
  EXPECT_EQ(j["producer"]["options"]["ocr_at_truth_size"], true);
  ASSERT_TRUE(j["metrics"]["cer"].is_number()) << j["ocr"].dump();
  EXPECT_LT(j["metrics"]["cer"].get<double>(), 0.05) << j["ocr"]["result_text"];
  EXPECT_GT(j["metrics"]["ms_ssim"].get<double>(), 0.95);
  // Without the flag the result is read at its own size.
  r = RunCommand(Evaluate(Args(dir / "big.png", "--no-flow")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(ReadJsonFile(out)["ocr"]["result_ocr_size"], Json::array({1760, 1360}));
}

TEST_F(EvaluateCli, MissingResultIsBadInputAndWritesNothing) {
  CommandResult r = RunCommand(Evaluate(Args(dir / "nope.png", "--no-ocr --no-flow")));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("nope.png: no such file"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(EvaluateCli, UnreadableOrEmptyImageIsBadInput) {
  std::ofstream(dir / "garbage.png") << "this is not a PNG file at all";
  CommandResult r = RunCommand(Evaluate(Args(dir / "garbage.png", "--no-ocr --no-flow")));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("garbage.png: not a readable image"), std::string::npos) << r.output;
  std::ofstream(dir / "empty.png");
  r = RunCommand(Evaluate(Args(dir / "empty.png", "--no-ocr --no-flow")));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // A broken ground truth is reported the same way, naming flat.png.
  std::ofstream(flat, std::ios::trunc) << "broken";
  r = RunCommand(Evaluate(Args(dir / "garbage.png", "--no-ocr --no-flow")));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("flat.png: not a readable image"), std::string::npos) << r.output;
}

TEST_F(EvaluateCli, DataSetWithoutGroundTruthIsSkippedWithANote) {
  fs::remove_all(data / "ground_truth");
  CommandResult r = RunCommand(Evaluate(Args(dir / "whatever.png")));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no ground_truth/flat.png; nothing to evaluate"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(EvaluateCli, BadUsageAndMissingFolders) {
  CommandResult r = RunCommand(Evaluate("--data " + Quote(data.string()) + " --result x.png"));
  EXPECT_EQ(r.exit_code, 2) << r.output;  // no --out
  r = RunCommand(Evaluate("--data " + Quote((dir / "absent").string()) + " --result x.png --out " +
                          Quote(out.string())));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("absent: no such data set folder"), std::string::npos) << r.output;
  r = RunCommand(
      Evaluate(Args(flat, "--no-ocr --no-flow --mesh-dir " + Quote((dir / "no-meshes").string()))));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("mesh3d.ply: no such file"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

// (evaluate --pdf on a real PDF: PdfCli.EvaluateMeasuresItsTextLayerAndSize.)
TEST_F(EvaluateCli, APdfThatIsMissingOrNotAPdfIsBadInput) {
  auto measure = [&](const fs::path& pdf, const std::string& extra = "") {
    return RunCommand(Evaluate("--data " + Quote(data.string()) + " --pdf " + Quote(pdf.string()) +
                               " --out " + Quote(out.string()) + extra));
  };
  CommandResult r = measure(dir / "nope.pdf");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("nope.pdf: no such file"), std::string::npos) << r.output;
  std::ofstream(dir / "empty.pdf");
  r = measure(dir / "empty.pdf");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("empty.pdf: not a PDF poppler can read"), std::string::npos) << r.output;
  std::ofstream(dir / "flat.pdf") << "%PDF-1.4 but nothing after it";
  r = measure(dir / "flat.pdf");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("flat.pdf: "), std::string::npos) << r.output;
  r = measure(dir / "empty.pdf", " --result " + Quote(flat.string()));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = measure(dir / "empty.pdf", " --front-end");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // Without the true text there is nothing to measure against.
  fs::remove(data / "ground_truth/text.txt");
  r = measure(dir / "nope.pdf");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no ground_truth/text.txt"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(EvaluateCli, UnwritableOutputIsExitFour) {
  std::ofstream(dir / "a_file") << "x";
  out = dir / "a_file" / "metrics.json";  // a folder that cannot exist
  CommandResult r = RunCommand(Evaluate(Args(flat, "--no-ocr --no-flow")));
  EXPECT_EQ(r.exit_code, 4) << r.output;
}

// ---- baseline -------------------------------------------------------------

std::string Baseline(const std::string& args) {
  return Quote(StageBinary("baseline").string()) + " " + args;
}

TEST(BaselineCli, MissingInputsNameTheFile) {
  TempDir dir;
  const fs::path data = MakeDataSet(dir / "set");
  const std::string common = " --data " + Quote(data.string()) + " --work " +
                             Quote((dir / "work").string()) + " --out " +
                             Quote((dir / "out.png").string());
  CommandResult r = RunCommand(Baseline("--method homography" + common));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("10_sfm/cameras.json: no such file (run sfm first)"), std::string::npos)
      << r.output;

  // A minimal sfm output, but no boundary: homography needs it.
  fs::create_directories(dir / "work" / "10_sfm");
  std::ofstream(dir / "work" / "10_sfm" / "cameras.json") << R"({"format": "docunfold.cameras",
    "version": 1, "producer": {"stage": "sfm", "version": "0"}, "reference": "a.jpg",
    "views": [{"image": "a.jpg", "width": 880, "height": 680,
               "K": [[800,0,439.5],[0,800,339.5],[0,0,1]], "R": [[1,0,0],[0,1,0],[0,0,1]],
               "t": [0,0,0]}]})";
  cv::imwrite((dir / "work" / "10_sfm" / "reference.png").string(),
              cv::imread((data / "ground_truth" / "flat.png").string()));
  r = RunCommand(Baseline("--method homography" + common));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("boundary.json: no such file"), std::string::npos) << r.output;

  // Corners that enclose nothing are refused with a JSON pointer.
  fs::create_directories(dir / "work" / "20_boundary");
  std::ofstream(dir / "work" / "20_boundary" / "boundary.json")
      << R"({"format": "docunfold.boundary", "version": 1, "corners": [[1,1],[1,1],[1,1],[1,1]]})";
  r = RunCommand(Baseline("--method homography" + common));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("boundary.json:/corners: corners enclose no area"), std::string::npos)
      << r.output;

  // Good corners: the whole reference image back onto itself at flat.png's size.
  std::ofstream(dir / "work" / "20_boundary" / "boundary.json", std::ios::trunc)
      << R"({"format": "docunfold.boundary", "version": 1,
             "corners": [[-0.5,-0.5],[879.5,-0.5],[879.5,679.5],[-0.5,679.5]]})";
  r = RunCommand(Baseline("--method homography" + common));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat back = cv::imread((dir / "out.png").string());
  const cv::Mat flat = cv::imread((data / "ground_truth" / "flat.png").string());
  ASSERT_EQ(back.size(), flat.size());
  EXPECT_LT(cv::norm(back, flat, cv::NORM_L1) / double(flat.total() * 3), 0.5);

  // The oracle needs the true surface and cameras.
  r = RunCommand(Baseline("--method oracle" + common));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("cameras.json: no such file (oracle)"), std::string::npos) << r.output;
  fs::remove_all(data / "ground_truth");
  r = RunCommand(Baseline("--method oracle" + common));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("the oracle needs ground truth"), std::string::npos) << r.output;

  r = RunCommand(Baseline("--method magic" + common));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = RunCommand(Baseline("--method homography --crop-to-seen" + common));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--crop-to-seen applies to the oracles only"), std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace docunfold::testing
