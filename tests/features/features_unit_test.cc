// detect-features on drawn pages whose lines are known exactly: text lines
// (upright, upside down, and bent at a crease), table rules, the page outline
// kept out; bad masks; and the geometric helpers.
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/errors.h"
#include "stages/detect-features/detect_features.h"
#include "stages/detect-features/feature_parts.h"

namespace docunfold::features {
namespace {

// Ordinary English: its letters have far more ascenders than descenders,
// which is what tells the baseline side (a line crowded with g, j, p, q, y
// would not).
constexpr const char* kLine = "The committee reviewed the annual statement, and it was accepted.";

struct Page {
  cv::Mat3b image;
  cv::Mat1b mask;
  std::vector<double> baselines;  // y of each text line (image rows)
  std::vector<double> rules;      // y of each rule's centre
};

// A grey table of `size` with a white page over `page`, its mask set there.
void BlankPage(cv::Size size, const cv::Rect& page, Page* p) {
  p->image = cv::Mat3b(size, cv::Vec3b(90, 90, 90));
  p->mask = cv::Mat1b::zeros(size);
  p->mask(page).setTo(255);
  p->image(page).setTo(cv::Scalar(240, 240, 240));
}

// A grey table with a white page: text lines (Hershey font; putText's origin
// is the baseline) and, below them, three horizontal rules 2 px thick.
Page DrawPage() {
  Page p;
  BlankPage({1200, 900}, {150, 80, 900, 760}, &p);
  for (int y = 160; y < 560; y += 30) {
    cv::putText(p.image, kLine, {200, y}, cv::FONT_HERSHEY_COMPLEX, 0.7, cv::Scalar(20, 20, 20), 1,
                cv::LINE_AA);
    p.baselines.push_back(y);
  }
  for (int y = 640; y <= 760; y += 60) {
    cv::rectangle(p.image, cv::Rect(200, y - 1, 800, 2), cv::Scalar(30, 30, 30), cv::FILLED);
    p.rules.push_back(y - 0.5);
  }
  return p;
}

// Distance from a segment's points (every pixel) to the nearest of the
// horizontal lines y = ys[i].
double WorstOffset(const Segment& s, const std::vector<double>& ys) {
  double worst = 0;
  const cv::Point2d a = s.points.front(), b = s.points.back();
  const int steps = std::max(1, int(cv::norm(b - a)));
  for (int k = 0; k <= steps; ++k) {
    const cv::Point2d q = a + (b - a) * (double(k) / steps);
    double best = 1e300;
    for (double y : ys) best = std::min(best, std::abs(q.y - y));
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(DetectFeatures, TextBaselinesAndRuleCentres) {
  const Page p = DrawPage();
  const FeaturesResult r = DetectFeatures(p.image, p.mask, {});
  ASSERT_GT(r.text_segments, 0);
  ASSERT_EQ(r.edge_segments, 3);
  EXPECT_FALSE(r.text_upside_down);
  ASSERT_TRUE(r.text_down);  // the reader's down: image down
  EXPECT_GT(r.text_down->y, 0.99);
  double text_length = 0;
  for (const Segment& s : r.segments) {
    ASSERT_GE(s.points.size(), 2u);
    if (s.kind == "text") {
      // Antialiased strokes reach about a pixel past putText's baseline.
      EXPECT_LE(WorstOffset(s, p.baselines), 1.5);
      text_length += cv::norm(s.points.back() - s.points.front());
    } else {
      EXPECT_EQ(s.kind, "edge");
      EXPECT_LE(WorstOffset(s, p.rules), 1.0);  // centre lines, not edges
      EXPECT_GE(cv::norm(s.points.back() - s.points.front()), 700);
    }
  }
  // Most of every line's length is found.
  EXPECT_GE(text_length, 0.6 * 600 * double(p.baselines.size()));
}

// A table below the text: dark row rules every 20 px and a faint column rule
// one pixel wide, slanted, crossing them. LSD stops the column rule's edges
// at every row rule, so only joined does it give one segment.
TEST(DetectFeatures, AThinColumnRuleCutByRowRulesComesOutWhole) {
  Page p = DrawPage();
  p.image(cv::Rect(150, 580, 900, 260)).setTo(cv::Scalar(240, 240, 240));
  for (int y = 600; y <= 820; y += 20)
    cv::rectangle(p.image, cv::Rect(200, y - 1, 800, 2), cv::Scalar(30, 30, 30), cv::FILLED);
  const cv::Point2d top(400, 590), bottom(412, 830);
  cv::line(p.image, top, bottom, cv::Scalar(120, 120, 120), 1, cv::LINE_AA);
  auto longest_along_column = [&](const FeaturesOptions& options) {
    double longest = 0;
    const cv::Point2d dir = (bottom - top) * (1 / cv::norm(bottom - top));
    for (const Segment& s : DetectFeatures(p.image, p.mask, options).segments) {
      if (s.kind != "edge") continue;
      double worst = 0;
      for (const cv::Point2d& q : {s.points.front(), s.points.back()})
        worst = std::max(worst, std::abs((q - top).cross(dir)));
      if (worst <= 1.0) longest = std::max(longest, cv::norm(s.points.back() - s.points.front()));
    }
    return longest;
  };
  // LSD on the page enlarged twice (detect-features' choice for text under
  // 12 px high; this page's is 12.3 px, so it is asked for) finds the pieces.
  FeaturesOptions joined;
  joined.lsd_upscale = 2;
  FeaturesOptions unjoined = joined;
  unjoined.join_gap = 0;
  EXPECT_LT(longest_along_column(unjoined), 60);
  EXPECT_GT(longest_along_column(joined), 0.8 * cv::norm(bottom - top));
}

TEST(DetectFeatures, UpsideDownTextStillGivesBaselines) {
  Page p = DrawPage();
  cv::rotate(p.image, p.image, cv::ROTATE_180);
  cv::rotate(p.mask, p.mask, cv::ROTATE_180);
  std::vector<double> baselines;
  for (double y : p.baselines) baselines.push_back(p.image.rows - 1 - y);
  const FeaturesResult r = DetectFeatures(p.image, p.mask, {});
  ASSERT_GT(r.text_segments, 5);
  EXPECT_TRUE(r.text_upside_down);
  ASSERT_TRUE(r.text_down);
  EXPECT_LT(r.text_down->y, -0.99);
  for (const Segment& s : r.segments) {
    if (s.kind == "text") {
      EXPECT_LE(WorstOffset(s, baselines), 1.5);
    }
  }
}

TEST(DetectFeatures, TextLinesAreCutAtACrease) {
  // Bend the right half of the page up by 8 degrees about x = 600: every
  // text line kinks there. No segment may bridge the kink.
  const Page p = DrawPage();
  const double angle = 8 * CV_PI / 180;
  cv::Mat map_x(p.image.size(), CV_32F), map_y(p.image.size(), CV_32F);
  for (int y = 0; y < p.image.rows; ++y)
    for (int x = 0; x < p.image.cols; ++x) {
      const double dx = x - 600.0;
      const double sy = x > 600 ? y + dx * std::tan(angle) : y;  // source row
      map_x.at<float>(y, x) = float(x);
      map_y.at<float>(y, x) = float(sy);
    }
  cv::Mat3b bent;
  cv::Mat1b bent_mask;
  cv::remap(p.image, bent, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar(90, 90, 90));
  cv::remap(p.mask, bent_mask, map_x, map_y, cv::INTER_NEAREST);
  const FeaturesResult r = DetectFeatures(bent, bent_mask, {});
  ASSERT_GT(r.text_segments, 10);
  for (const Segment& s : r.segments) {
    if (s.kind != "text") continue;
    const double x0 = std::min(s.points.front().x, s.points.back().x);
    const double x1 = std::max(s.points.front().x, s.points.back().x);
    // A segment may reach a few pixels past the crease, not more.
    EXPECT_TRUE(x1 <= 606 || x0 >= 594) << "segment " << x0 << ".." << x1 << " bridges the crease";
  }
}

// Small text, slanted and JPEG-compressed, as in a photo: single letters
// put the baseline a pixel off (pixel grid, serifs, artefacts). Judged on the
// baseline's running median, far more of the lines' length comes out (as
// long pieces rather than many too short to keep), and no less exactly.
TEST(DetectFeatures, PixelNoiseDoesNotCutSmallSlantedText) {
  const Page p = DrawPage();
  const double angle_deg = 4, scale = 0.6;
  const cv::Point2f centre(600, 450);
  cv::Mat transform = cv::getRotationMatrix2D(centre, angle_deg, scale);
  cv::Mat3b photo;
  cv::Mat1b mask;
  cv::warpAffine(p.image, photo, transform, p.image.size(), cv::INTER_AREA, cv::BORDER_CONSTANT,
                 cv::Scalar(90, 90, 90));
  cv::warpAffine(p.mask, mask, transform, p.mask.size(), cv::INTER_NEAREST);
  std::vector<uchar> jpeg;
  cv::imencode(".jpg", photo, jpeg, {cv::IMWRITE_JPEG_QUALITY, 70});
  photo = cv::imdecode(jpeg, cv::IMREAD_COLOR);
  // The baselines as lines in the photo: points (200, y) and (1000, y) mapped.
  std::vector<cv::Point2d> ends;
  for (double y : p.baselines) {
    ends.emplace_back(200, y);
    ends.emplace_back(1000, y);
  }
  cv::transform(ends, ends, transform);
  std::vector<std::pair<cv::Point2d, cv::Point2d>> baselines;
  for (size_t k = 0; k + 1 < ends.size(); k += 2) baselines.emplace_back(ends[k], ends[k + 1]);
  auto measure = [&](double window) {
    FeaturesOptions options;
    options.bend_window = window;
    options.row_gap = 0;  // joining the words of a line would mend the cuts measured here
    double length = 0;
    for (const Segment& s : DetectFeatures(photo, mask, options).segments) {
      if (s.kind != "text") continue;
      double worst = 0;
      for (const cv::Point2d& q : {s.points.front(), s.points.back()}) {
        double best = 1e300;
        for (const auto& [a, b] : baselines)
          best = std::min(best, std::abs((q - a).cross(b - a)) / cv::norm(b - a));
        worst = std::max(worst, best);
      }
      EXPECT_LE(worst, 1.5) << "window " << window;
      length += cv::norm(s.points.back() - s.points.front());
    }
    return length;
  };
  const double raw = measure(0), median = measure(1);
  std::printf("text: %.0f px judged sample by sample, %.0f px on the median\n", raw, median);
  EXPECT_GE(median, 1.15 * raw);
}

TEST(DetectFeatures, PageOutlineIsNoFeature) {
  // A blank page: its outline is a strong straight edge, but not a feature.
  cv::Mat3b image(600, 800, cv::Vec3b(60, 60, 60));
  cv::Mat1b mask = cv::Mat1b::zeros(image.size());
  mask(cv::Rect(100, 100, 600, 400)).setTo(255);
  image.setTo(cv::Scalar(240, 240, 240), mask);
  EXPECT_TRUE(DetectFeatures(image, mask, {}).segments.empty());
}

TEST(DetectFeatures, BadMasksAreBadInput) {
  const Page p = DrawPage();
  EXPECT_THROW(DetectFeatures(p.image, cv::Mat1b::zeros(p.image.size()), {}), InputError);
  EXPECT_THROW(DetectFeatures(p.image, cv::Mat1b(100, 100, uchar(255)), {}), InputError);
}

TEST(FeatureHelpers, SplitWhereBentCutsAtTheKink) {
  std::vector<cv::Point2d> pts;
  for (int x = 0; x <= 100; ++x) pts.emplace_back(x, 0);
  for (int x = 101; x <= 200; ++x) pts.emplace_back(x, 0.1 * (x - 100));
  const auto pieces = detail::SplitWhereBent(pts, 1.0);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_NEAR(pieces[0].second, 100, 6);
  const auto straight =
      detail::SplitWhereBent(std::vector<cv::Point2d>(pts.begin(), pts.begin() + 101), 1.0);
  EXPECT_EQ(straight.size(), 1u);
}

TEST(FeatureHelpers, FitLineRecoversALine) {
  std::vector<cv::Point2d> pts;
  for (int k = 0; k < 50; ++k) pts.emplace_back(k, 3 + 0.5 * k + (k % 2 ? 0.2 : -0.2));
  const detail::LineFit fit = detail::FitLine(pts);
  EXPECT_NEAR(std::abs(fit.direction.y / fit.direction.x), 0.5, 1e-3);
  EXPECT_NEAR(fit.rms, 0.2 / std::sqrt(1.25), 0.02);
}

// A receipt: items on the left, prices on the right, a wide blank gap
// between them on each row's baseline.
Page DrawReceipt() {
  static const char* kItems[] = {"Butter", "Cheese",  "Bread", "Apples",  "Tomatoes", "Coffee",
                                 "Pasta",  "Yoghurt", "Soap",  "Milk 1L", "Rice 2kg", "Tea"};
  static const char* kPrices[] = {"5.54",  "12.37", "3.10", "7.69",  "14.03", "9.75",
                                  "10.81", "2.95",  "6.08", "11.52", "4.47",  "8.16"};
  Page p;
  BlankPage({1000, 600}, {100, 40, 800, 520}, &p);
  for (int k = 0; k < 12; ++k) {
    const int y = 90 + 36 * k;
    cv::putText(p.image, kItems[k], {160, y}, cv::FONT_HERSHEY_COMPLEX, 0.7, cv::Scalar(20, 20, 20),
                1, cv::LINE_AA);
    int base = 0;
    const cv::Size size = cv::getTextSize(kPrices[k], cv::FONT_HERSHEY_COMPLEX, 0.7, 1, &base);
    cv::putText(p.image, kPrices[k], {840 - size.width, y}, cv::FONT_HERSHEY_COMPLEX, 0.7,
                cv::Scalar(20, 20, 20), 1, cv::LINE_AA);
    p.baselines.push_back(y);
  }
  return p;
}

// Text segments reaching from the items (left of x = 300) to the prices
// (right of x = 760); every text segment must lie on a baseline.
int WholeRows(const FeaturesResult& r, const std::vector<double>& baselines) {
  int whole = 0;
  for (const Segment& s : r.segments) {
    if (s.kind != "text") continue;
    const double x0 = std::min(s.points.front().x, s.points.back().x);
    const double x1 = std::max(s.points.front().x, s.points.back().x);
    // Antialiased strokes reach about a pixel past putText's baseline, this
    // font's digits half a pixel farther than its letters; 2 px is what
    // evaluate counts as on a line.
    EXPECT_LE(WorstOffset(s, baselines), 2.0);
    whole += x0 < 300 && x1 > 760;
  }
  return whole;
}

// Most of the 12 rows come out whole; a short item whose few letters do not
// tell its direction ("Tea") may stay apart from its price.
TEST(DetectFeatures, ReceiptRowsAreJoinedAcrossTheirGap) {
  const Page p = DrawReceipt();
  EXPECT_GE(WholeRows(DetectFeatures(p.image, p.mask, {}), p.baselines), 9);
  FeaturesOptions unjoined;
  unjoined.row_gap = 0;
  EXPECT_EQ(WholeRows(DetectFeatures(p.image, p.mask, unjoined), p.baselines), 0);
}

TEST(DetectFeatures, ReceiptRowsTurnedAQuarterAreJoinedToo) {
  // Receipts are often photographed across: turned clockwise, a row runs
  // down the image. The segments are turned back to compare.
  const Page p = DrawReceipt();
  cv::Mat3b image;
  cv::Mat1b mask;
  cv::rotate(p.image, image, cv::ROTATE_90_CLOCKWISE);
  cv::rotate(p.mask, mask, cv::ROTATE_90_CLOCKWISE);
  FeaturesResult r = DetectFeatures(image, mask, {});
  for (Segment& s : r.segments)
    for (cv::Point2d& q : s.points) q = {q.y, p.image.rows - 1 - q.x};
  EXPECT_GE(WholeRows(r, p.baselines), 9);
}

TEST(DetectFeatures, ARuleAcrossTheGapKeepsATableRowsCellsApart) {
  Page p = DrawReceipt();
  cv::line(p.image, {500, 60}, {500, 520}, cv::Scalar(30, 30, 30), 2);  // a column rule
  EXPECT_EQ(WholeRows(DetectFeatures(p.image, p.mask, {}), p.baselines), 0);
}

// A corner curled over the page shows its blank back, of another grey,
// over the middle of rows 6 to 8: their items and prices lie in line
// across it but are on the page beneath. They stay apart; the other rows
// join as before.
TEST(DetectFeatures, NoRowIsJoinedAcrossACornerCurledOverIt) {
  Page p = DrawReceipt();
  const int whole_before = WholeRows(DetectFeatures(p.image, p.mask, {}), p.baselines);
  const std::vector<cv::Point> curl = {{380, 220}, {640, 228}, {625, 318}, {395, 312}};
  cv::fillConvexPoly(p.image, curl, cv::Scalar(205, 205, 205), cv::LINE_AA);
  const FeaturesResult r = DetectFeatures(p.image, p.mask, {});
  for (const Segment& s : r.segments) {
    if (s.kind != "text") continue;
    const double y = 0.5 * (s.points.front().y + s.points.back().y);
    const double x0 = std::min(s.points.front().x, s.points.back().x);
    const double x1 = std::max(s.points.front().x, s.points.back().x);
    if (y > 220 && y < 318)
      EXPECT_FALSE(x0 < 400 && x1 > 620) << "a row across the curl at y " << y;
  }
  EXPECT_GE(WholeRows(r, p.baselines), whole_before - 3);
}

// OnePaperLayerTest on a page of grey 200 with the gap from (100, 100) to
// (500, 100), text 12 px high, letters above the baseline (up = -y).
bool OneLayer(const cv::Mat1b& grey, const cv::Mat1i& labels) {
  return detail::OnePaperLayerTest(grey, labels, {0, -1}, 12)({100, 100}, {500, 100});
}

TEST(FeatureHelpers, OnePaperLayerAcrossShadingAndInk) {
  cv::Mat1b grey(200, 600, uchar(200));
  cv::Mat1i labels = cv::Mat1i::zeros(grey.size());
  EXPECT_TRUE(OneLayer(grey, labels));
  // Shading drifting from 220 to 160 along the gap (27 %, 2 levels a text
  // height) is one layer.
  cv::Mat1b shaded = grey.clone();
  for (int x = 0; x < shaded.cols; ++x) shaded.col(x).setTo(220 - 60 * x / 600);
  EXPECT_TRUE(OneLayer(shaded, labels));
  // So is a dark mark in the gap (a dot, a stray letter): ink is left out.
  cv::Mat1b marked = grey.clone();
  cv::rectangle(marked, cv::Rect(290, 86, 10, 12), cv::Scalar(30), cv::FILLED);
  cv::Mat1i marked_labels = labels.clone();
  marked_labels(cv::Rect(290, 86, 10, 12)).setTo(1);
  EXPECT_TRUE(OneLayer(marked, marked_labels));
  // A blank flap of grey 180 (10 % darker) over the middle of the gap is
  // another layer; one of 190 (5 %) is taken for shading.
  for (const auto& [flap, one_layer] : {std::pair{180, false}, std::pair{190, true}}) {
    cv::Mat1b curled = grey.clone();
    curled(cv::Rect(250, 0, 120, 200)).setTo(flap);
    EXPECT_EQ(OneLayer(curled, labels), one_layer) << flap;
  }
}

TEST(FeatureHelpers, OnePaperHueAcrossShadingNotAcrossAnotherPaper) {
  // Cream paper (B 190, G 205, R 215), the gap from (100, 100) to (500,
  // 100), text 12 px high, letters above the baseline.
  const cv::Mat3b paper(200, 600, cv::Vec3b(190, 205, 215));
  const cv::Mat1i labels = cv::Mat1i::zeros(paper.size());
  auto one_hue = [&](const cv::Mat3b& colour) {
    return detail::OnePaperHueTest(colour, labels, {0, -1}, 12)({100, 100}, {500, 100});
  };
  EXPECT_TRUE(one_hue(paper));
  // A shadow over the middle of the gap, 30 % darker: the same hue.
  cv::Mat3b shaded = paper.clone();
  shaded(cv::Rect(250, 0, 120, 200)).setTo(cv::Vec3b(133, 143, 150));
  EXPECT_TRUE(one_hue(shaded));
  // A neutral grey flap over the whole gap and no farther (its edges
  // within a text height of the pieces), as bright as the paper.
  cv::Mat3b flap = paper.clone();
  flap(cv::Rect(103, 0, 394, 200)).setTo(cv::Vec3b(203, 203, 203));
  EXPECT_FALSE(one_hue(flap));
}

// A piece of a baseline as JoinBaselinePieces takes it: samples every 4 px
// from x0 to x1 on y = y0 + slope * (x - x0), a quarter pixel up and down
// in turn (the pixel grid).
detail::BaselinePiece Piece(double x0, double x1, double y0, double slope, int chain) {
  detail::BaselinePiece piece;
  for (double x = x0; x <= x1; x += 4)
    piece.samples.emplace_back(x, y0 + slope * (x - x0) + (int(x) % 8 ? 0.25 : -0.25));
  piece.first = piece.samples.front();
  piece.last = piece.samples.back();
  piece.characters = int((x1 - x0) / 10);
  piece.height = 16;
  piece.chain = chain;
  return piece;
}

// Text 12 px high (x-height), tolerance 1.5 px, gaps up to 60 text heights.
std::vector<std::vector<int>> Join(const std::vector<detail::BaselinePiece>& pieces) {
  return detail::JoinBaselinePieces(pieces, {1, 0}, 12, 1.5, 60 * 12);
}

TEST(FeatureHelpers, RowJoinBridgesAWideGapOnOneBaseline) {
  // "Butter" and "5.54": 60 and 40 px long, 340 px apart, on a line sloping
  // by 1 degree.
  const double slope = std::tan(CV_PI / 180);
  const auto groups =
      Join({Piece(100, 160, 200, slope, 0), Piece(500, 540, 200 + 400 * slope, slope, 1)});
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0], (std::vector<int>{0, 1}));
}

TEST(FeatureHelpers, RowJoinKeepsRowsApart) {
  // The next row's price, 2.2 text heights lower, continues no item alone;
  // with both rows there, each item takes its own price.
  EXPECT_EQ(Join({Piece(100, 160, 200, 0, 0), Piece(500, 540, 226.4, 0, 1)}).size(), 2u);
  auto groups = Join({Piece(100, 160, 200, 0, 0), Piece(100, 148, 226.4, 0, 1),
                      Piece(500, 540, 200, 0, 2), Piece(492, 540, 226.4, 0, 3)});
  std::sort(groups.begin(), groups.end());
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0], (std::vector<int>{0, 2}));
  EXPECT_EQ(groups[1], (std::vector<int>{1, 3}));
}

TEST(FeatureHelpers, RowJoinOnlyOnAPageOfGappedRows) {
  // Running text: ten whole lines, two of them cut by a washed-out band (a
  // fold's highlight) 5 text heights wide. Two gapped rows of ten: nothing
  // is joined.
  std::vector<detail::BaselinePiece> text;
  for (int row = 0; row < 10; ++row) {
    const double y = 200 + 30 * row;
    if (row == 3 || row == 6) {
      text.push_back(Piece(100, 300, y, 0, int(text.size())));
      text.push_back(Piece(360, 600, y, 0, int(text.size())));
    } else {
      text.push_back(Piece(100, 600, y, 0, int(text.size())));
    }
  }
  EXPECT_EQ(Join(text).size(), text.size());
  // A receipt: every row an item and a price far apart. Each row is joined.
  std::vector<detail::BaselinePiece> receipt;
  for (int row = 0; row < 10; ++row) {
    const double y = 200 + 30 * row;
    receipt.push_back(Piece(100, 160, y, 0, int(receipt.size())));
    receipt.push_back(Piece(500, 540, y, 0, int(receipt.size())));
  }
  EXPECT_EQ(Join(receipt).size(), 10u);
  // A till roll: besides its ten priced rows, thirty short pieces that join
  // nothing (VAT codes, header words, pieces of separators). A quarter of
  // the groups bridge a gap, but nearly all of the rows' length: joined.
  std::vector<detail::BaselinePiece> roll = receipt;
  for (int k = 0; k < 30; ++k) roll.push_back(Piece(100, 120, 520 + 30 * k, 0, int(roll.size())));
  EXPECT_EQ(Join(roll).size(), 40u);
}

TEST(FeatureHelpers, RowJoinDoesNotBridgeACrease) {
  // A crease in the gap at x = 330: beyond it the row turns by 3 degrees,
  // its two parts meeting there. One line through both pieces fits each
  // closely, but turns against the item by half the kink.
  const double turn = std::tan(3 * CV_PI / 180);
  const auto groups =
      Join({Piece(100, 160, 200, 0, 0), Piece(500, 540, 200 + 170 * turn, turn, 1)});
  EXPECT_EQ(groups.size(), 2u);
  // Pieces of one chain were cut apart by the bend test: never joined back.
  EXPECT_EQ(Join({Piece(100, 160, 200, 0, 0), Piece(164, 240, 200, 0, 0)}).size(), 2u);
}

}  // namespace
}  // namespace docunfold::features
