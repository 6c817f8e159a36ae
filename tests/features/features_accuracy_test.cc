// detect-features against the ground truth of every data set, in every view
// (photo, true camera, true page region): precision (share of the detected
// segments' length within 2 px of a true line of a matching kind) and recall
// (share of the true text and rule lines' visible length that detected
// segments cover). Text segments follow baselines, which is what the truth's
// text lines are (synth writes baselines; for sets without features.json
// they are read off flat.png, see LinesFromFlatScan), so both are compared
// directly. The figures are evaluate's (stages/evaluate/front_end.h), the
// same that `evaluate --front-end` gives the benchmark for a pipeline run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "stages/detect-features/detect_features.h"
#include "stages/evaluate/front_end.h"
#include "tests/boundary/eval_support.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

using features::FeaturesResult;
using features::Segment;

using evaluate::LineFigures;
using evaluate::SegmentIndex;

void Print(const std::string& what, const LineFigures& f) {
  std::printf(
      "%-36s precision %.3f (text %.3f, edge %.3f)  recall %.3f (text %.3f, rules %.3f)  "
      "segments %d text, %d edge\n",
      what.c_str(), f.precision, f.precision_text, f.precision_edge, f.recall, f.recall_text,
      f.recall_rule, f.text_segments, f.edge_segments);
}

std::vector<FeatureSegment> Segments(const FeaturesResult& r) {
  std::vector<FeatureSegment> out;
  for (const Segment& s : r.segments) {
    FeatureSegment f{s.kind, {}};
    for (const cv::Point2d& p : s.points) f.points.emplace_back(p.x, p.y);
    out.push_back(std::move(f));
  }
  return out;
}

void MaybeWriteDebug(const GroundTruth& gt, const PinholeCamera& cam, const cv::Mat& image,
                     const cv::Mat1b& mask, const FeaturesResult& r, const std::string& what) {
  const char* dir = std::getenv("DOCUNFOLD_DEBUG_DIR");
  if (!dir) return;
  cv::Mat out = features::DrawFeaturesOverlay(image, mask, r, 100000);
  for (const TrueLine& l : evaluate::SeeTruth(gt, cam).lines)
    for (size_t k = 0; k + 1 < l.points.size(); ++k)
      cv::line(out, cv::Point(int(l.points[k].x()), int(l.points[k].y())),
               cv::Point(int(l.points[k + 1].x()), int(l.points[k + 1].y())), cv::Scalar(0, 200, 0),
               1);
  std::string name = what;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  cv::imwrite(std::string(dir) + "/features_" + name + ".png", out);
}

class FeaturesOnDataSet : public ::testing::TestWithParam<fs::path> {};

// Precision and recall on the most frontal view (sfm's likely reference) are
// asserted; every view is measured and printed, and precision must hold in
// each.
TEST_P(FeaturesOnDataSet, SegmentsLieOnTrueLines) {
  auto gt = LoadGroundTruth(GetParam());
  ASSERT_TRUE(gt);
  const int frontal = MostFrontalView(*gt);
  const bool recall_required = evaluate::LineRecallRequired(*gt);
  double length = 0, good = 0;
  for (size_t v = 0; v < gt->cameras.views.size(); ++v) {
    const PinholeCamera& cam = gt->cameras.views[v];
    const cv::Mat image = ReadView(*gt, cam);
    ASSERT_FALSE(image.empty()) << cam.image;
    const evaluate::TruthInView truth = evaluate::SeeTruth(*gt, cam);
    const FeaturesResult r = features::DetectFeatures(image, truth.page, {});
    const LineFigures f = evaluate::MeasureLines(truth, Segments(r));
    const std::string what =
        DataSetName(GetParam()) + "/" + cam.image + (int(v) == frontal ? " (frontal)" : "");
    Print(what, f);
    MaybeWriteDebug(*gt, cam, image, truth.page, r, what);
    length += f.detected_length;
    good += f.precision * f.detected_length;
    if (int(v) == frontal) {
      EXPECT_GE(f.precision, evaluate::kMinLinePrecision) << what;
      if (recall_required) {
        EXPECT_GE(f.recall, evaluate::kMinLineRecall) << what;
      }
      EXPECT_GT(f.text_segments + f.edge_segments, 0) << what;
    }
  }
  std::printf("%s: precision over all views %.3f%s\n", DataSetName(GetParam()).c_str(),
              length > 0 ? good / length : 1.0, recall_required ? " (recall required)" : "");
}

// The lines read off flat.png agree with synth's own on the sets that have
// both, so they can stand in for the truth where synth's are missing: nearly
// all of their length lies within 1 px of synth's lines, and on text pages
// and tables they cover most of synth's text lines. (On receipts they miss
// the gaps synth's lines span between item and price, and small print.)
TEST_P(FeaturesOnDataSet, FlatScanLinesAgreeWithSynth) {
  auto gt = LoadGroundTruth(GetParam());
  ASSERT_TRUE(gt);
  if (gt->lines.empty()) GTEST_SKIP() << "no features.json to compare with";
  SegmentIndex synth_index(16), flat_index(16);
  for (const TrueLine& l : gt->lines) synth_index.AddPolyline(l.points);
  double length = 0, good = 0;
  for (const TrueLine& l : LinesFromFlatScan(*gt)) {
    const Eigen::Vector2d a = l.points.front(), b = l.points.back();
    flat_index.Add(a, b);
    const int steps = std::max(1, int((b - a).norm()));
    for (int j = 0; j < steps; ++j) {
      length += (b - a).norm() / steps;
      good += synth_index.Distance(a + (b - a) * ((j + 0.5) / steps)) <= 1.0
                  ? (b - a).norm() / steps
                  : 0;
    }
  }
  double synth_text = 0, covered = 0;
  for (const TrueLine& l : gt->lines) {
    if (l.kind != "text") continue;
    for (size_t k = 0; k + 1 < l.points.size(); ++k) {
      const Eigen::Vector2d a = l.points[k], b = l.points[k + 1];
      const int steps = std::max(1, int((b - a).norm()));
      for (int j = 0; j < steps; ++j) {
        synth_text += (b - a).norm() / steps;
        covered += flat_index.Distance(a + (b - a) * ((j + 0.5) / steps)) <= 1.0
                       ? (b - a).norm() / steps
                       : 0;
      }
    }
  }
  std::printf(
      "%s: %.3f of the flat-scan lines within 1 px of synth's; they cover %.3f of "
      "synth's text lines\n",
      DataSetName(GetParam()).c_str(), length > 0 ? good / length : 0.0,
      synth_text > 0 ? covered / synth_text : 0.0);
  EXPECT_GE(good, 0.9 * length);
  if (evaluate::LineRecallRequired(*gt)) {
    EXPECT_GE(covered, 0.8 * synth_text);
  }
}

// Receipts, the weakest pages: a row is an item and its price far apart on
// one baseline, and detect-features joins it across the gap. Their truth
// spans the gap (synth's, and LinesFromFlatScan's rows on one baseline). The
// most frontal view only (about a second a set).
LineFigures MeasureReceipt(const fs::path& set) {
  auto gt = LoadGroundTruth(set);
  EXPECT_TRUE(gt);
  if (!gt) return {};
  const PinholeCamera& cam = gt->cameras.views[size_t(MostFrontalView(*gt))];
  const cv::Mat image = ReadView(*gt, cam);
  EXPECT_FALSE(image.empty()) << cam.image;
  if (image.empty()) return {};
  const evaluate::TruthInView truth = evaluate::SeeTruth(*gt, cam);
  const FeaturesResult r = features::DetectFeatures(image, truth.page, {});
  const LineFigures f = evaluate::MeasureLines(truth, Segments(r));
  Print(DataSetName(set) + "/" + cam.image + " (rows)", f);
  MaybeWriteDebug(*gt, cam, image, truth.page, r, DataSetName(set) + "/" + cam.image + " rows");
  return f;
}

TEST(FeaturesOnReceipts, SampleRowsAreFoundWhole) {
  for (const char* name : {"set03", "set07"}) {
    const LineFigures f = MeasureReceipt(SampleDir(name));
    EXPECT_GE(f.precision, 0.97) << name;
    EXPECT_GE(f.recall_text, 0.6) << name;
  }
}

TEST(FeaturesOnReceipts, RealisticRowsAreFoundWhole) {
  if (RealisticDir().empty() || !fs::exists(RealisticDir() / "r03" / "ground_truth"))
    GTEST_SKIP() << "no ../shared/realistic/r03";
  const LineFigures f = MeasureReceipt(RealisticDir() / "r03");
  EXPECT_GE(f.precision, 0.97);
  EXPECT_GE(f.recall_text, 0.6);
}

// The hard receipts: r07 has a corner curled over the page, r09 a panel
// standing steep. In the raw photo with the true page region r09's rows
// read 0.580 (its steep panel's 13 rows, a third of its text, are not
// found; in sfm's reference view, as the pipeline runs, 0.605): r09 is held
// to 0.55 (docs/decisions/detect-features.md, "A join stays on one layer
// of paper").
TEST(FeaturesOnReceipts, HardRowsAreFoundWhole) {
  const fs::path hard = RealisticHardDir();
  for (const auto& [name, min_recall] : {std::pair{"r07", 0.6}, std::pair{"r09", 0.55}}) {
    if (hard.empty() || !fs::exists(hard / name / "ground_truth")) {
      GTEST_SKIP() << "no ../shared/realistic-hard/" << name;
    }
    const LineFigures f = MeasureReceipt(hard / name);
    EXPECT_GE(f.precision, 0.97) << name;
    EXPECT_GE(f.recall_text, min_recall) << name;
  }
}

// Till rolls as synth prints them (--roll 58, two creases): monospaced
// items, prices right-aligned far from them, weight rows, separators, a
// larger TOTAL, VAT lines. Their text height is that of the digits and
// capitals, and the lone VAT codes and header words outnumber the rows.
// Made at test time (two views, about 2.5 s a roll), measured in the most
// frontal view against synth's truth (a separator row is a rule there, with
// no ink on its baseline). Text recall there: 0.484 and 0.484 (0.123 and
// 0.206 before rows were judged gapped by length and sampled against their
// own letters' band), precision 0.979 and 0.970. In sfm's reference view of
// the same roll 0.654 (docs/decisions/detect-features.md, "A till roll's
// rows").
TEST(FeaturesOnReceipts, TillRollRowsAreFoundWhole) {
  TempDir dir;
  for (const char* seed : {"201", "3"}) {
    const fs::path set = dir / seed;
    const CommandResult made =
        RunCommand(Quote(StageBinary("synth").string()) +
                   " --kind receipt --roll 58 --creases 2 --angle-min 30 --angle-max 70 --views 2 "
                   "--background wood --seed " +
                   seed + " --out " + Quote(set.string()));
    ASSERT_EQ(made.exit_code, 0) << made.output;
    const LineFigures f = MeasureReceipt(set);
    EXPECT_GE(f.precision, 0.96) << seed;
    EXPECT_GE(f.recall_text, 0.4) << seed;
  }
}

std::string SetName(const ::testing::TestParamInfo<fs::path>& info) {
  std::string s = DataSetName(info.param);
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(AllSets, FeaturesOnDataSet, ::testing::ValuesIn(DataSetsWithTruth()),
                         SetName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(FeaturesOnDataSet);

}  // namespace
}  // namespace docunfold::testing
