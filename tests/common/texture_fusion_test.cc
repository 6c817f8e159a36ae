// FuseTexture on a flat page photographed twice: the reference from afar
// (it resolves the page coarsely), a second photo close up over the lower
// part of the page, 30 % darker, with a glare spot. The close photo colours
// what it sees; levelled, it meets the reference without a step; the glare
// is taken from the reference instead. And two photos that resolve the
// page equally finely, one of them shaken.
#include "common/texture_fusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace docunfold {
namespace {

constexpr int kPageW = 600, kPageH = 800;  // output pixels: 1 per mm
constexpr double kMetresPerPixel = 0.001;
const cv::Point kGlare(300, 560);  // page pixels, inside the close photo
constexpr double kGlareSigma = 14;

struct Scene {
  cv::Mat3b page;   // the truth at the output's size
  cv::Mat1b paper;  // paper pixels away from print
  FusionSurface surface;
  std::vector<FusionView> views;
};

cv::Mat3b MakePrintedPage() {
  cv::Mat3b page(kPageH, kPageW, cv::Vec3b(222, 230, 236));
  cv::RNG rng(7);
  for (int y = 60; y < kPageH - 40; y += 28)
    for (int x = 40; x < kPageW - 60; x += 14)
      if (rng.uniform(0, 6) != 0)
        cv::putText(page, std::string(1, char('a' + rng.uniform(0, 26))), cv::Point(x, y),
                    cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
  return page;
}

// A camera at `centre` (world, metres) looking along +z at the page in the
// plane z = 0.
PinholeCamera Camera(const Eigen::Vector3d& centre) {
  PinholeCamera c;
  c.width = 800;
  c.height = 1000;
  c.K << 1000, 0, 399.5, 0, 1000, 499.5, 0, 0, 1;
  c.R = Eigen::Matrix3d::Identity();
  c.t = -centre;
  return c;
}

// The page photographed by `camera` on a dark table, times `exposure`, with
// sensor noise.
cv::Mat3b Photograph(const cv::Mat3b& page, const PinholeCamera& camera, double exposure,
                     int seed) {
  // Page pixel (u, v) -> world (X, Y, 0) -> photo pixel.
  Eigen::Matrix3d S;
  S << kMetresPerPixel, 0, 0.5 * kMetresPerPixel, 0, kMetresPerPixel, 0.5 * kMetresPerPixel, 0, 0,
      1;
  Eigen::Matrix3d Rt;
  Rt << camera.R.col(0), camera.R.col(1), camera.t;
  const Eigen::Matrix3d H = camera.K * Rt * S;
  cv::Matx33d h;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) h(i, j) = H(i, j);
  cv::Mat3f lit;
  page.convertTo(lit, CV_32F, exposure);
  cv::Mat3f photo;
  cv::warpPerspective(lit, photo, h, cv::Size(camera.width, camera.height), cv::INTER_AREA,
                      cv::BORDER_CONSTANT, cv::Scalar(50, 60, 70) * exposure);
  cv::Mat3f noise(photo.size());
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, 2);
  cv::Mat3b out;
  cv::Mat3f(photo + noise).convertTo(out, CV_8U);
  return out;
}

Scene MakeScene() {
  Scene s;
  s.page = MakePrintedPage();
  cv::Mat grey;
  cv::cvtColor(s.page, grey, cv::COLOR_BGR2GRAY);
  cv::Mat1b print = grey < 200;
  cv::dilate(print, print, cv::Mat::ones(11, 11, CV_8U));
  s.paper = print == 0;
  // A 9 x 9 vertex grid over the page.
  constexpr int kN = 9;
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) {
      const double u = i / double(kN - 1), v = j / double(kN - 1);
      s.surface.world.emplace_back(u * kPageW * kMetresPerPixel, v * kPageH * kMetresPerPixel, 0);
      s.surface.pixel.emplace_back(u * kPageW - 0.5, v * kPageH - 0.5);
    }
  for (int j = 0; j + 1 < kN; ++j)
    for (int i = 0; i + 1 < kN; ++i) {
      const int a = j * kN + i;
      s.surface.triangles.push_back({a, a + 1, a + kN + 1});
      s.surface.triangles.push_back({a, a + kN + 1, a + kN});
    }
  s.surface.width = kPageW;
  s.surface.height = kPageH;
  // The reference from 1.6 m: 0.625 photo pixels per page pixel.
  const PinholeCamera far = Camera({0.3, 0.4, -1.6});
  // The close photo from 0.6 m over the lower part: 1.67 per page pixel.
  const PinholeCamera close = Camera({0.3, 0.6, -0.6});
  cv::Mat3b close_photo = Photograph(s.page, close, 0.7, 2);
  // Glare: a bright spot on the close photo.
  const Eigen::Vector2d g = close.Project(
      Eigen::Vector3d((kGlare.x + 0.5) * kMetresPerPixel, (kGlare.y + 0.5) * kMetresPerPixel, 0));
  const double sigma = kGlareSigma * 1000 / 600.0;
  for (int y = 0; y < close_photo.rows; ++y)
    for (int x = 0; x < close_photo.cols; ++x) {
      const double d2 = (x - g.x()) * (x - g.x()) + (y - g.y()) * (y - g.y());
      const double add = 150 * std::exp(-0.5 * d2 / (sigma * sigma));
      for (int c = 0; c < 3; ++c)
        close_photo(y, x)[c] = cv::saturate_cast<uchar>(close_photo(y, x)[c] + add);
    }
  s.views = {{far, {}, Photograph(s.page, far, 1.0, 1), {}, "far"},
             {close, {}, close_photo, {}, "close"}};
  return s;
}

// fused - truth, per pixel (grey), blurred a little: both resample the page
// at other resolutions.
cv::Mat1f Difference(const cv::Mat3b& fused, const cv::Mat3b& truth) {
  cv::Mat a, b;
  cv::cvtColor(fused, a, cv::COLOR_BGR2GRAY);
  cv::cvtColor(truth, b, cv::COLOR_BGR2GRAY);
  cv::Mat1f fa, fb;
  a.convertTo(fa, CV_32F);
  b.convertTo(fb, CV_32F);
  cv::GaussianBlur(fa, fa, cv::Size(0, 0), 1.5);
  cv::GaussianBlur(fb, fb, cv::Size(0, 0), 1.5);
  return fa - fb;
}

TEST(TextureFusion, CloserPhotoColoursWhatItSeesLevelledWithoutStepsAndWithoutGlare) {
  const Scene s = MakeScene();
  const FusedTexture fused = FuseTexture(s.surface, s.views);
  ASSERT_EQ(fused.image.size(), cv::Size(kPageW, kPageH));
  EXPECT_EQ(fused.surface_pixels, long(kPageW) * kPageH);
  EXPECT_LT(fused.unseen, 0.001);
  ASSERT_EQ(fused.views.size(), 2u);
  // The close photo sees y >= 300 (x 60..540); it resolves it better.
  EXPECT_GT(fused.views[1].share, 0.3);
  EXPECT_LT(fused.views[1].share, 0.5);
  // Levelled to the reference: its gain undoes the 30 % darker exposure.
  EXPECT_NEAR(fused.views[1].gain[1], 1 / 0.7, 0.05);

  const cv::Mat1f diff = Difference(fused.image, s.page);
  // No step across the seams: paper within 10 pixels of a seam differs
  // from the truth by the same on both sides (the page's noise averages out).
  cv::Mat1b seam(fused.label.size(), uchar(0));
  for (int y = 1; y < seam.rows; ++y)
    for (int x = 1; x < seam.cols; ++x)
      if (fused.label(y, x) < 2 && (fused.label(y, x - 1) != fused.label(y, x) ||
                                    fused.label(y - 1, x) != fused.label(y, x)))
        seam(y, x) = 255;
  ASSERT_GT(cv::countNonZero(seam), 200);
  cv::Mat1b near_seam;
  cv::dilate(seam, near_seam, cv::Mat::ones(21, 21, CV_8U));
  cv::Mat1b glare_area(seam.size(), uchar(0));
  cv::circle(glare_area, kGlare, int(4 * kGlareSigma), 255, cv::FILLED);
  const cv::Mat1b away_from_glare = glare_area == 0;
  double mean_side[2];
  for (int v = 0; v < 2; ++v) {
    const cv::Mat1b side = near_seam & s.paper & (fused.label == v) & away_from_glare;
    ASSERT_GT(cv::countNonZero(side), 500) << "view " << v;
    mean_side[v] = cv::mean(diff, side)[0];
  }
  EXPECT_LT(std::abs(mean_side[0] - mean_side[1]), 2.0)
      << "far side " << mean_side[0] << ", close side " << mean_side[1];
  // The glare is gone: where it was brightest, the page is as bright as the truth.
  cv::Mat1b glare_core(seam.size(), uchar(0));
  cv::circle(glare_core, kGlare, int(1.5 * kGlareSigma), 255, cv::FILLED);
  double worst = 0;
  cv::minMaxLoc(diff, nullptr, &worst, nullptr, nullptr, glare_core & s.paper);
  EXPECT_LT(worst, 12) << "glare left in the fused page";
  // And the page as a whole is the truth at the reference's exposure.
  EXPECT_LT(std::abs(cv::mean(diff, s.paper)[0]), 2.0);
}

TEST(TextureFusion, ReferenceOnlyWhenNoOtherPhotoSeesBetter) {
  Scene s = MakeScene();
  // The second photo as far away as the reference: nothing to gain.
  s.views[1].camera = Camera({0.3, 0.5, -1.6});
  s.views[1].photo = Photograph(s.page, s.views[1].camera, 0.7, 3);
  const FusedTexture fused = FuseTexture(s.surface, s.views);
  EXPECT_GT(fused.views[0].share, 0.99);
}

TEST(TextureFusion, PartsNoPhotoSeesAreCountedUnseen) {
  Scene s = MakeScene();
  s.views.resize(1);
  // Only the upper 60 % of the page in the frame.
  s.views[0].camera = Camera({0.3, 0.1, -0.8});
  s.views[0].photo = Photograph(s.page, s.views[0].camera, 1.0, 4);
  const FusedTexture fused = FuseTexture(s.surface, s.views);
  EXPECT_GT(fused.unseen, 0.2);
  EXPECT_LT(fused.unseen, 0.6);
  EXPECT_EQ(cv::countNonZero(fused.label == kFusionUnseen),
            long(std::lround(fused.unseen * fused.surface_pixels)));
}

// A photo smeared by a hand's shake: a 13-pixel line at 30 degrees.
cv::Mat3b Shaken(const cv::Mat3b& photo) {
  cv::Mat1f kernel(15, 15, 0.f);
  cv::line(kernel, cv::Point(1, 10), cv::Point(13, 4), cv::Scalar(1), 1, cv::LINE_AA);
  kernel /= cv::sum(kernel)[0];
  cv::Mat3b out;
  cv::filter2D(photo, out, -1, kernel);
  return out;
}

// Two photos that resolve the page equally finely (both at 1 photo pixel per
// page pixel or finer), one of them shaken.
Scene MakeEqualScene(bool shake_reference, bool shake_other) {
  Scene s = MakeScene();
  s.views[0].camera = Camera({0.3, 0.4, -1.0});
  s.views[0].photo = Photograph(s.page, s.views[0].camera, 1.0, 5);
  // 0.9 m away over the lower part: it sees y >= 100.
  s.views[1].camera = Camera({0.3, 0.55, -0.9});
  s.views[1].photo = Photograph(s.page, s.views[1].camera, 0.8, 6);
  if (shake_reference) s.views[0].photo = Shaken(s.views[0].photo);
  if (shake_other) s.views[1].photo = Shaken(s.views[1].photo);
  return s;
}

TEST(TextureFusion, AShakenPhotoColoursOnlyWhatNoSharpOneSees) {
  {
    const Scene s = MakeEqualScene(false, false);
    const FusedTexture fused = FuseTexture(s.surface, s.views);
    EXPECT_EQ(fused.views[0].sharpness, 1);
    EXPECT_EQ(fused.views[1].sharpness, 1);
    EXPECT_GT(fused.views[0].share, 0.95);  // the reference's preference
  }
  {
    const Scene s = MakeEqualScene(false, true);
    const FusedTexture fused = FuseTexture(s.surface, s.views);
    EXPECT_EQ(fused.views[0].sharpness, 1);
    EXPECT_LT(fused.views[1].sharpness, 0.5);
    EXPECT_GT(fused.views[0].share, 0.95);
  }
  {
    // The reference shaken: the other photo colours all it sees (7/8 of the
    // page) but the reference's border band.
    const Scene s = MakeEqualScene(true, false);
    const FusedTexture fused = FuseTexture(s.surface, s.views);
    EXPECT_LT(fused.views[0].sharpness, 0.5);
    EXPECT_EQ(fused.views[1].sharpness, 1);
    EXPECT_GT(fused.views[1].share, 0.8);
    // Its print is sharp: the fused page is nearer the truth than the
    // shaken reference's rendering of it.
    const FusedTexture shaken_only = FuseTexture(s.surface, {s.views[0]});
    cv::Mat1b seen_by_other(s.page.size(), uchar(0));
    seen_by_other(cv::Rect(40, 200, kPageW - 80, kPageH - 240)).setTo(255);
    const double fused_error = cv::mean(cv::abs(Difference(fused.image, s.page)), seen_by_other)[0];
    const double shaken_error =
        cv::mean(cv::abs(Difference(shaken_only.image, s.page)), seen_by_other)[0];
    EXPECT_LT(fused_error, 0.7 * shaken_error) << fused_error << " vs " << shaken_error;
  }
}

}  // namespace
}  // namespace docunfold
