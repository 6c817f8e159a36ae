// The print of a rectified page straightened in the image: a page of text
// bent by a known smooth displacement comes back straight, and a straight
// or blank page is left as it is.
#include "stages/render/print_straightening.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "tests/support/test_support.h"

namespace docunfold::render {
namespace {

// A page of text: rows of random words of varying length, 22 px apart.
cv::Mat3b TextPage(int width, int height) {
  cv::Mat3b page(height, width, cv::Vec3b(235, 238, 240));
  cv::RNG rng(7);
  for (int y = 40; y < height - 30; y += 22) {
    int x = 30 + rng.uniform(0, 40);
    const int end = width - 30 - rng.uniform(0, width / 3);
    while (x < end) {
      std::string word;
      for (int n = rng.uniform(2, 9); n > 0; --n) word += char('a' + rng.uniform(0, 26));
      cv::putText(page, word, cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                  cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
      x += 10 * int(word.size()) + 12;
    }
  }
  return page;
}

// The bend: bent(x, y) = page(x + bx, y + by), rows by a sine across the
// page, columns by one down it, `amplitude` px.
struct Bend {
  double amplitude;
  cv::Size size;
  Eigen::Vector2d At(double x, double y) const {
    return {0.6 * amplitude * std::sin(2 * M_PI * y / size.height),
            amplitude * std::sin(2 * M_PI * x / size.width)};
  }
};

cv::Mat3b Bent(const cv::Mat3b& page, const Bend& bend) {
  cv::Mat1f mx(page.size()), my(page.size());
  for (int y = 0; y < page.rows; ++y)
    for (int x = 0; x < page.cols; ++x) {
      const Eigen::Vector2d d = bend.At(x, y);
      mx(y, x) = float(x + d.x());
      my(y, x) = float(y + d.y());
    }
  cv::Mat3b out;
  cv::remap(page, out, mx, my, cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  return out;
}

// The 95th percentile, over the pixels near print, of how far the
// straightened image's pixel lies from where the unbent page has it:
// straightened(x, y) = bent(map(x, y)) = page(map + bend(map)).
double Residual95(const cv::Mat3b& page, const Straightening& s, const Bend& bend) {
  cv::Mat grey;
  cv::cvtColor(page, grey, cv::COLOR_BGR2GRAY);
  cv::Mat1b near_print = grey < 150;
  cv::dilate(near_print, near_print, cv::Mat(), cv::Point(-1, -1), 6);
  std::vector<double> r;
  for (int y = 0; y < page.rows; ++y)
    for (int x = 0; x < page.cols; ++x) {
      if (!near_print(y, x)) continue;
      const Eigen::Vector2d m(s.map_x(y, x), s.map_y(y, x));
      r.push_back((m + bend.At(m.x(), m.y()) - Eigen::Vector2d(x, y)).norm());
    }
  std::nth_element(r.begin(), r.begin() + r.size() * 95 / 100, r.end());
  return r[r.size() * 95 / 100];
}

TEST(PrintStraightening, BentRowsAndColumnsComeOutStraight) {
  const cv::Mat3b page = TextPage(520, 720);
  const Bend bend{3.0, page.size()};
  const Straightening s = FindStraightening(Bent(page, bend), StraightenOptions{});
  const Straightening identity = FindStraightening(page, StraightenOptions{.enabled = false});
  EXPECT_GT(Residual95(page, identity, bend), 2.5);
  // The rows' bend goes; the columns' is not found in ragged text (below).
  EXPECT_LT(Residual95(page, s, bend), 1.9);
  EXPECT_GT(s.rows.shifts_found, s.rows.strips * s.rows.windows / 2);
  EXPECT_GT(s.rows.max_shift_px, 2.5);
  EXPECT_LT(s.rows.max_shift_px, 4.0);
}

TEST(PrintStraightening, RulesDownThePageAreStraightenedToo) {
  // Rules down the page (a table's), bent with the rows: straight again
  // along their length; the text beside them moves with their windows.
  const cv::Mat3b text = TextPage(520, 720);
  cv::Mat3b page = text.clone(), rules(text.size(), cv::Vec3b(235, 238, 240));
  for (const int x : {20, 150, 300, 500}) {
    cv::line(page, {x, 20}, {x, 700}, {30, 30, 30}, 2);
    cv::line(rules, {x, 20}, {x, 700}, {30, 30, 30}, 2);
  }
  const Bend bend{3.0, page.size()};
  const Straightening s = FindStraightening(Bent(page, bend), StraightenOptions{});
  EXPECT_GT(s.columns.max_shift_px, 1.0);
  // How far each rule's pixels lie across it from where they belong, before
  // (up to 1.8 px, the bend) and after.
  std::vector<double> before, after;
  for (const int x : {20, 150, 300, 500})
    for (int y = 40; y < 690; y += 2) {
      before.push_back(std::abs(bend.At(x, y).x()));
      const Eigen::Vector2d m(s.map_x(y, x), s.map_y(y, x));
      after.push_back(std::abs(m.x() + bend.At(m.x(), m.y()).x() - x));
    }
  auto p90 = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() * 9 / 10, v.end());
    return v[v.size() * 9 / 10];
  };
  EXPECT_GT(p90(before), 1.6);
  EXPECT_LT(p90(after), 0.8 * p90(before)) << p90(after);
}

TEST(PrintStraightening, AStraightPageMovesLittle) {
  const cv::Mat3b page = TextPage(520, 720);
  const Straightening s = FindStraightening(page, StraightenOptions{});
  EXPECT_LT(s.rows.max_shift_px, 1.0);
  EXPECT_LT(s.columns.max_shift_px, 0.5);
  EXPECT_LT(Residual95(page, s, Bend{0, page.size()}), 0.5);
}

TEST(PrintStraightening, APhotographsTextureIsLeftAlone) {
  // The wooden table in a corner of set02's first photo: grain whose
  // profiles correlate from strip to strip, without the blank gaps of print.
  const cv::Mat photo = cv::imread((testing::SampleDir("set02") / "images/view_00.jpg").string());
  if (photo.empty()) GTEST_SKIP() << "no sample set02";
  const cv::Mat wood = photo(cv::Rect(0, 0, 700, 500)).clone();
  const Straightening s = FindStraightening(wood, StraightenOptions{});
  EXPECT_EQ(s.rows.shifts_found + s.columns.shifts_found, 0);
  EXPECT_EQ(s.rows.max_shift_px + s.columns.max_shift_px, 0);
  // Without the contrast test, the grain is moved.
  StraightenOptions any;
  any.min_row_contrast = 0;
  EXPECT_GT(FindStraightening(wood, any).rows.max_shift_px, 1.0);
}

TEST(PrintStraightening, BlankTinyOrDisabledIsTheIdentity) {
  const cv::Mat3b blank(600, 400, cv::Vec3b(230, 230, 230));
  const cv::Mat3b tiny = TextPage(520, 720)(cv::Rect(100, 100, 40, 30)).clone();
  StraightenOptions off;
  off.enabled = false;
  for (const auto& [image, options] :
       {std::pair{blank, StraightenOptions{}}, std::pair{tiny, StraightenOptions{}},
        std::pair{cv::Mat3b(TextPage(520, 720)), off}}) {
    const Straightening s = FindStraightening(image, options);
    EXPECT_EQ(s.rows.shifts_found + s.columns.shifts_found, 0);
    EXPECT_EQ(cv::norm(ApplyStraightening(image, s, cv::INTER_CUBIC), image, cv::NORM_INF), 0);
  }
}

TEST(PrintStraightening, LargeImagesAreAnalysedAtTheWorkingSize) {
  // The same bend at twice the size: found on a copy of about work_pixels,
  // applied at full size.
  cv::Mat3b page;
  cv::resize(TextPage(520, 720), page, cv::Size(1040, 1440), 0, 0, cv::INTER_CUBIC);
  const Bend bend{6.0, page.size()};
  const Straightening s = FindStraightening(Bent(page, bend), StraightenOptions{});
  EXPECT_LT(s.rows.strips, 30);  // strips of the working copy, not of the image
  EXPECT_GT(s.rows.max_shift_px, 5.0);
  EXPECT_LT(Residual95(page, s, bend), 3.8);
}

}  // namespace
}  // namespace docunfold::render
