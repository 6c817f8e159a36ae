// RemoveShading on a synthetic page: paper lit unevenly (a fold's darker
// panel with a sharp step, a soft shadow across it), black text, a coloured
// banner. After removal the paper is one colour, the text as dark against it
// as before, and the banner keeps its colour.
#include "common/shading.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace docunfold {
namespace {

struct Page {
  cv::Mat3b image;
  cv::Mat1b paper;   // paper pixels, away from text and banner
  cv::Mat1b text;    // text strokes
  cv::Mat1b banner;  // the banner's inside
  cv::Mat1f light;   // the light factor applied
};

constexpr int kWidth = 700, kHeight = 1000;
const cv::Vec3f kPaper(232, 238, 242);   // BGR, slightly warm paper
const cv::Vec3f kBanner(160, 110, 150);  // purple

Page MakePage() {
  Page p;
  cv::Mat3f albedo(kHeight, kWidth, kPaper);
  p.banner = cv::Mat1b::zeros(kHeight, kWidth);
  cv::rectangle(p.banner, cv::Rect(0, 0, kWidth, 150), 255, cv::FILLED);
  albedo.setTo(kBanner, p.banner);
  p.text = cv::Mat1b::zeros(kHeight, kWidth);
  for (int y = 220; y < 950; y += 24)
    for (int x = 40; x < kWidth - 60; x += 11)
      if ((x / 11 + y / 24) % 7 != 0)
        cv::putText(p.text, "a", cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, 0.5, 255, 1);
  albedo.setTo(cv::Vec3f(30, 30, 30), p.text);
  // Light: a fold at y = 600 below which the panel gets 0.65 of it, a soft
  // diagonal shadow (0.8 at its middle), and a gentle falloff to the right.
  p.light = cv::Mat1f(kHeight, kWidth);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      float l = y < 600 ? 1.0f : 0.65f;
      const float d = (x - 0.5f * y - 100) / 60.f;
      l *= 1 - 0.2f * std::exp(-d * d);
      l *= 1 - 0.15f * x / kWidth;
      p.light(y, x) = l;
    }
  p.image = cv::Mat3b(kHeight, kWidth);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) p.image(y, x) = albedo(y, x) * p.light(y, x);
  cv::Mat1b near_text;
  cv::dilate(p.text, near_text, cv::Mat::ones(9, 9, CV_8U));
  p.paper = (near_text == 0) & (p.banner == 0);
  return p;
}

// Spread of the paper's grey level: 95th minus 5th percentile.
double PaperSpread(const cv::Mat3b& image, const cv::Mat1b& mask) {
  cv::Mat1b grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  std::vector<int> values;
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x)
      if (mask(y, x)) values.push_back(grey(y, x));
  std::sort(values.begin(), values.end());
  return values[values.size() * 95 / 100] - values[values.size() * 5 / 100];
}

TEST(RemoveShading, PaperBecomesEvenAndPrintKeepsItsContrastAndColour) {
  const Page page = MakePage();
  ASSERT_GT(PaperSpread(page.image, page.paper), 60);  // the shading is there
  const ShadingRemoval r = RemoveShading(page.image);
  ASSERT_EQ(r.image.size(), page.image.size());
  ASSERT_EQ(r.image.type(), CV_8UC3);
  EXPECT_LE(PaperSpread(r.image, page.paper), 10);
  std::printf("paper spread %.0f -> %.0f grey levels\n", PaperSpread(page.image, page.paper),
              PaperSpread(r.image, page.paper));
  // Paper maps to the well-lit paper's colour.
  const cv::Scalar paper_mean = cv::mean(r.image, page.paper);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(paper_mean[c], kPaper[c] * 0.95, 15) << c;
  // Text stays dark next to the paper on the dark panel as on the bright one.
  cv::Mat1b text_top = page.text.clone(), text_bottom = page.text.clone();
  text_top.rowRange(600, kHeight).setTo(0);
  text_bottom.rowRange(0, 620).setTo(0);
  cv::Mat1b core;
  cv::erode(page.text, core, cv::Mat::ones(1, 1, CV_8U));
  const double top = cv::mean(r.image, text_top & core)[1];
  const double bottom = cv::mean(r.image, text_bottom & core)[1];
  EXPECT_LT(top, 0.6 * paper_mean[1]);
  EXPECT_LT(bottom, 0.6 * paper_mean[1]);
  // The banner is print, not paper in shadow: its colour is kept (as lit).
  cv::Mat1b banner_core;
  cv::erode(page.banner, banner_core, cv::Mat::ones(21, 21, CV_8U));
  const cv::Scalar banner = cv::mean(r.image, banner_core);
  const cv::Scalar banner_before = cv::mean(page.image, banner_core);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(banner[c], banner_before[c], 0.15 * banner_before[c]) << c;
  std::printf(
      "text %.0f / %.0f on paper %.0f; banner (%.0f %.0f %.0f) was (%.0f %.0f "
      "%.0f)\n",
      top, bottom, paper_mean[1], banner[0], banner[1], banner[2], banner_before[0],
      banner_before[1], banner_before[2]);
}

TEST(RemoveShading, EmptyGreyAndEvenImagesAreHandled) {
  EXPECT_TRUE(RemoveShading(cv::Mat()).image.empty());
  // Grey in, grey out.
  cv::Mat1b grey(200, 300, uchar(200));
  grey.colRange(150, 300).setTo(120);  // a shaded half
  const ShadingRemoval g = RemoveShading(grey);
  ASSERT_EQ(g.image.type(), CV_8UC1);
  EXPECT_LE(std::abs(int(g.image.at<uchar>(100, 50)) - int(g.image.at<uchar>(100, 250))), 4);
  // Evenly lit paper stays as it is.
  const cv::Mat3b even(120, 90, cv::Vec3b(210, 220, 225));
  const ShadingRemoval e = RemoveShading(even);
  EXPECT_LE(cv::norm(e.image, even, cv::NORM_INF), 1);
}

}  // namespace
}  // namespace docunfold
