// detect-features against the ground truth of every data set, in every view
// (photo, true camera, true page region): precision (share of the detected
// segments' length within 2 px of a true line of a matching kind) and recall
// (share of the true text and rule lines' visible length that detected
// segments cover). Text segments follow baselines, which is what the truth's
// text lines are (synth writes baselines; for sets without features.json
// they are read off flat.png, see flat_truth.h), so both are compared
// directly.
#include <cstdio>
#include <cstdlib>
#include <map>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "stages/detect-features/detect_features.h"
#include "tests/boundary/eval_support.h"
#include "tests/features/flat_truth.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

using features::FeaturesResult;
using features::Segment;

constexpr double kTolerancePx = 2.0;
constexpr double kMinPrecision = 0.95;
constexpr double kMinRecall = 0.5;

// Segments of polylines bucketed on a grid, for distance queries.
class SegmentIndex {
 public:
  explicit SegmentIndex(double cell) : cell_(cell) {}
  void Add(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const int id = int(segs_.size());
    segs_.push_back({a, b});
    const int x0 = Cell(std::min(a.x(), b.x())), x1 = Cell(std::max(a.x(), b.x()));
    const int y0 = Cell(std::min(a.y(), b.y())), y1 = Cell(std::max(a.y(), b.y()));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) grid_[{x, y}].push_back(id);
  }
  // Distance to the nearest segment, or +inf beyond about one cell.
  double Distance(const Eigen::Vector2d& p) const {
    double best = std::numeric_limits<double>::infinity();
    const int cx = Cell(p.x()), cy = Cell(p.y());
    for (int y = cy - 1; y <= cy + 1; ++y)
      for (int x = cx - 1; x <= cx + 1; ++x) {
        auto it = grid_.find({x, y});
        if (it == grid_.end()) continue;
        for (int id : it->second) {
          const auto& [a, b] = segs_[size_t(id)];
          const Eigen::Vector2d d = b - a;
          const double t = d.squaredNorm() > 0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
          best = std::min(best, (a + t * d - p).norm());
        }
      }
    return best;
  }

 private:
  int Cell(double v) const { return int(std::floor(v / cell_)); }
  double cell_;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segs_;
  std::map<std::pair<int, int>, std::vector<int>> grid_;
};

struct Figures {
  double precision_text = 1, precision_edge = 1, precision = 1;
  double recall_text = 0, recall_rule = 0, recall = 0;
  double detected_length = 0, true_length = 0;
  int text_segments = 0, edge_segments = 0;
};

// Truth lines of a data set: synth's, or read off flat.png.
std::vector<TrueLine> TruthLines(const GroundTruth& gt) {
  return gt.lines.empty() ? LinesFromFlatScan(gt) : gt.lines;
}

Figures Measure(GroundTruth gt, const PinholeCamera& cam, const FeaturesResult& r,
                const cv::Mat1b& region) {
  gt.lines = TruthLines(gt);
  const std::vector<TrueLine> lines = TrueLinesInView(gt, cam, 2.0);
  SegmentIndex text_index(8), edge_index(8);
  for (const TrueLine& l : lines)
    for (size_t k = 0; k + 1 < l.points.size(); ++k)
      (l.kind == "text" ? text_index : edge_index).Add(l.points[k], l.points[k + 1]);
  Figures f;
  double good_text = 0, all_text = 0, good_edge = 0, all_edge = 0;
  SegmentIndex found_text(8), found_edge(8);
  for (const Segment& s : r.segments) {
    const bool text = s.kind == "text";
    (text ? f.text_segments : f.edge_segments)++;
    for (size_t k = 0; k + 1 < s.points.size(); ++k) {
      const Eigen::Vector2d a(s.points[k].x, s.points[k].y), b(s.points[k + 1].x, s.points[k + 1].y);
      (text ? found_text : found_edge).Add(a, b);
      const int steps = std::max(1, int(std::ceil((b - a).norm())));
      const double piece = (b - a).norm() / steps;
      for (int j = 0; j < steps; ++j) {
        const Eigen::Vector2d p = a + (b - a) * ((j + 0.5) / steps);
        const bool good = (text ? text_index : edge_index).Distance(p) <= kTolerancePx;
        (text ? all_text : all_edge) += piece;
        (text ? good_text : good_edge) += good ? piece : 0.0;
      }
    }
  }
  f.detected_length = all_text + all_edge;
  f.precision_text = all_text > 0 ? good_text / all_text : 1.0;
  f.precision_edge = all_edge > 0 ? good_edge / all_edge : 1.0;
  f.precision = f.detected_length > 0 ? (good_text + good_edge) / f.detected_length : 1.0;
  // Recall over text and rule lines inside the region features are sought in.
  double cov_text = 0, len_text = 0, cov_rule = 0, len_rule = 0;
  for (const TrueLine& l : lines) {
    if (l.kind == "border") continue;
    const bool text = l.kind == "text";
    for (size_t k = 0; k + 1 < l.points.size(); ++k) {
      const Eigen::Vector2d m = 0.5 * (l.points[k] + l.points[k + 1]);
      const int x = int(std::lround(m.x())), y = int(std::lround(m.y()));
      if (x < 0 || y < 0 || x >= region.cols || y >= region.rows || !region(y, x)) continue;
      const double len = (l.points[k + 1] - l.points[k]).norm();
      const bool covered = (text ? found_text : found_edge).Distance(m) <= kTolerancePx;
      (text ? len_text : len_rule) += len;
      (text ? cov_text : cov_rule) += covered ? len : 0.0;
    }
  }
  f.true_length = len_text + len_rule;
  f.recall_text = len_text > 0 ? cov_text / len_text : 0;
  f.recall_rule = len_rule > 0 ? cov_rule / len_rule : 0;
  f.recall = f.true_length > 0 ? (cov_text + cov_rule) / f.true_length : 0;
  return f;
}

// Text pages and tables must have half their lines covered; receipts and
// posters (short lines, few of them) are only measured.
bool RecallRequired(const GroundTruth& gt) {
  const fs::path synth = gt.root / "ground_truth" / "synth.json";
  if (fs::exists(synth)) {
    const std::string text = ReadJsonFile(synth).dump();
    return text.find("\"kind\":\"text\"") != std::string::npos ||
           text.find("\"kind\":\"table\"") != std::string::npos;
  }
  int text = 0, rules = 0;
  double long_text = 0;
  for (const TrueLine& l : TruthLines(gt)) {
    if (l.kind == "rule") ++rules;
    if (l.kind != "text") continue;
    ++text;
    if ((l.points.back() - l.points.front()).norm() > 0.4 * gt.flat_width) ++long_text;
  }
  return rules >= 10 || (text >= 20 && long_text >= 0.5 * text);
}

void Print(const std::string& what, const Figures& f) {
  std::printf("%-36s precision %.3f (text %.3f, edge %.3f)  recall %.3f (text %.3f, rules %.3f)  "
              "segments %d text, %d edge\n",
              what.c_str(), f.precision, f.precision_text, f.precision_edge, f.recall,
              f.recall_text, f.recall_rule, f.text_segments, f.edge_segments);
}

void MaybeWriteDebug(const GroundTruth& gt, const PinholeCamera& cam, const cv::Mat& image,
                     const cv::Mat1b& mask, const FeaturesResult& r, const std::string& what) {
  const char* dir = std::getenv("DOCUNFOLD_DEBUG_DIR");
  if (!dir) return;
  GroundTruth g = gt;
  g.lines = TruthLines(gt);
  cv::Mat out = features::DrawFeaturesOverlay(image, mask, r, 100000);
  for (const TrueLine& l : TrueLinesInView(g, cam, 2.0))
    for (size_t k = 0; k + 1 < l.points.size(); ++k)
      cv::line(out, cv::Point(int(l.points[k].x()), int(l.points[k].y())),
               cv::Point(int(l.points[k + 1].x()), int(l.points[k + 1].y())),
               cv::Scalar(0, 200, 0), 1);
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
  const bool recall_required = RecallRequired(*gt);
  double length = 0, good = 0;
  for (size_t v = 0; v < gt->cameras.views.size(); ++v) {
    const PinholeCamera& cam = gt->cameras.views[v];
    const cv::Mat image = ReadView(*gt, cam);
    ASSERT_FALSE(image.empty()) << cam.image;
    const cv::Mat1b mask = TruePageMask(*gt, cam);
    const FeaturesResult r = features::DetectFeatures(image, mask, {});
    // The region the stage searched: the mask less its default margin.
    const int margin = std::max(4, int(std::lround(0.006 * std::hypot(cam.width, cam.height))));
    cv::Mat1b region;
    cv::erode(mask, region, cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                                      cv::Size(2 * margin + 1, 2 * margin + 1)));
    const Figures f = Measure(*gt, cam, r, region);
    const std::string what = DataSetName(GetParam()) + "/" + cam.image +
                             (int(v) == frontal ? " (frontal)" : "");
    Print(what, f);
    MaybeWriteDebug(*gt, cam, image, mask, r, what);
    length += f.detected_length;
    good += f.precision * f.detected_length;
    if (int(v) == frontal) {
      EXPECT_GE(f.precision, kMinPrecision) << what;
      if (recall_required) {
        EXPECT_GE(f.recall, kMinRecall) << what;
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
  for (const TrueLine& l : gt->lines)
    for (size_t k = 0; k + 1 < l.points.size(); ++k) synth_index.Add(l.points[k], l.points[k + 1]);
  double length = 0, good = 0;
  for (const TrueLine& l : LinesFromFlatScan(*gt)) {
    const Eigen::Vector2d a = l.points.front(), b = l.points.back();
    flat_index.Add(a, b);
    const int steps = std::max(1, int((b - a).norm()));
    for (int j = 0; j < steps; ++j) {
      length += (b - a).norm() / steps;
      good += synth_index.Distance(a + (b - a) * ((j + 0.5) / steps)) <= 1.0 ? (b - a).norm() / steps : 0;
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
        covered += flat_index.Distance(a + (b - a) * ((j + 0.5) / steps)) <= 1.0 ? (b - a).norm() / steps : 0;
      }
    }
  }
  std::printf("%s: %.3f of the flat-scan lines within 1 px of synth's; they cover %.3f of "
              "synth's text lines\n",
              DataSetName(GetParam()).c_str(), length > 0 ? good / length : 0.0,
              synth_text > 0 ? covered / synth_text : 0.0);
  EXPECT_GE(good, 0.9 * length);
  if (RecallRequired(*gt)) {
    EXPECT_GE(covered, 0.8 * synth_text);
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
