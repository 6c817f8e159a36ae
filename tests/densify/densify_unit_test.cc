// densify's building blocks, and Run on a rendered scene: a tilted page
// with rows of "words" on a darker table, seen by four cameras.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <functional>
#include <opencv2/imgproc.hpp>
#include <random>

#include "stages/densify/densify.h"
#include "tests/support/look_at.h"

namespace docunfold::testing {
namespace {

using densify::DensifyInputs;
using densify::DensifyOptions;
using densify::DensifyResult;

PinholeCamera LookAt(const std::string& image, const Eigen::Vector3d& centre,
                     const Eigen::Vector3d& target) {
  return LookAtCamera(image, centre, target, 800, 600, 1000);
}

TEST(Densify, ScaledCameraSeesTheResizedPixel) {
  const PinholeCamera c = LookAt("a.jpg", {0.1, -0.2, 0}, {0, 0, 1});
  const PinholeCamera half = densify::ScaleCamera(c, 0.5);
  EXPECT_EQ(half.width, 400);
  EXPECT_EQ(half.height, 300);
  const Eigen::Vector3d X(0.05, 0.1, 1.1);
  const Eigen::Vector2d full = c.Project(X), small = half.Project(X);
  // cv::resize's pixel centres: x' = (x + 0.5) s - 0.5.
  EXPECT_NEAR(small.x(), (full.x() + 0.5) * 0.5 - 0.5, 1e-9);
  EXPECT_NEAR(small.y(), (full.y() + 0.5) * 0.5 - 0.5, 1e-9);
}

// A white page with black text lines on a brown table, seen from above: page
// points (white, or black on the text) are kept, table points that the other
// photos saw behind a raised page (brown where the reference shows white) are
// hidden, and all of it under a darker exposure of the other photos.
TEST(Densify, PointsOfAnotherColourThanTheReferenceShowsAreHidden) {
  const PinholeCamera camera = LookAt("ref", {0, 0, 0}, {0, 0, 1});
  cv::Mat reference(600, 800, CV_8UC3, cv::Scalar(40, 90, 150));  // brown table (BGR)
  cv::rectangle(reference, cv::Rect(200, 100, 400, 400), cv::Scalar(245, 245, 245), -1);
  for (int y = 150; y < 450; y += 20)
    cv::line(reference, {220, y}, {580, y}, cv::Scalar(20, 20, 20), 2);
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<uint8_t, 3>> colours;
  std::vector<bool> expected;
  const double exposure = 0.8;  // the photos COLMAP coloured the points from were darker
  auto add = [&](int u, int v, const std::array<uint8_t, 3>& rgb, bool hidden) {
    const Eigen::Vector3d ray = camera.K.inverse() * Eigen::Vector3d(u, v, 1);
    points.push_back(ray * 1.2);
    std::array<uint8_t, 3> seen;
    for (int c = 0; c < 3; ++c) seen[c] = uint8_t(std::lround(rgb[c] * exposure));
    colours.push_back(seen);
    expected.push_back(hidden);
  };
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> col(210, 590), row(110, 490), gap(0, 14);
  // Paper between the text lines (10 px from them).
  for (int i = 0; i < 60; ++i) add(col(rng), 160 + 20 * gap(rng), {245, 245, 245}, false);
  for (int y = 150; y < 450; y += 60) add(400, y + 1, {20, 20, 20}, false);   // on the text
  for (int i = 0; i < 15; ++i) add(col(rng), row(rng), {150, 90, 40}, true);  // table behind
  add(100, 300, {150, 90, 40}, false);  // table where the reference shows table
  std::vector<int> indices(points.size());
  for (size_t i = 0; i < indices.size(); ++i) indices[i] = int(i);
  points.push_back({0, 0, -1});  // behind the camera: not judged
  colours.push_back({150, 90, 40});
  indices.push_back(int(points.size()) - 1);
  expected.push_back(false);

  const std::vector<bool> hidden = densify::HiddenInReference(points, colours, indices, camera,
                                                              reference, densify::HiddenOptions{});
  ASSERT_EQ(hidden.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(hidden[i], expected[i]) << i;

  // Without colours, or with one colour for all, nothing is judged.
  const std::vector<bool> none =
      densify::HiddenInReference(points, {}, indices, camera, reference, densify::HiddenOptions{});
  EXPECT_EQ(std::count(none.begin(), none.end(), true), 0);
  const std::vector<std::array<uint8_t, 3>> grey(points.size(), {128, 128, 128});
  const std::vector<bool> same = densify::HiddenInReference(points, grey, indices, camera,
                                                            reference, densify::HiddenOptions{});
  EXPECT_EQ(std::count(same.begin(), same.end(), true), 0);
}

TEST(Densify, TriangulationIsExactWithoutNoise) {
  const PinholeCamera a = LookAt("a", {0, 0, 0}, {0, 0, 1});
  const PinholeCamera b = LookAt("b", {0.3, 0, 0.05}, {0, 0, 1});
  const PinholeCamera c = LookAt("c", {-0.1, 0.25, 0}, {0, 0, 1});
  const Eigen::Vector3d X(0.07, -0.04, 0.93);
  const Eigen::Vector3d Y =
      densify::Triangulate({&a, &b, &c}, {a.Project(X), b.Project(X), c.Project(X)});
  EXPECT_LT((X - Y).norm(), 1e-9);
  // One view cannot place a point: the result is not finite or not X.
  const Eigen::Vector3d Z = densify::Triangulate({&a, &a}, {a.Project(X), a.Project(X)});
  EXPECT_FALSE(Z.allFinite() && (Z - X).norm() < 1e-6);
}

// The page: origin at its top-left corner, `along`/`down` its axes (metres
// per texel), a texture of rows of dark words on white.
struct Scene {
  Eigen::Vector3d origin, along, down;
  cv::Mat1b texture;
  CameraSet cameras;
  std::vector<cv::Mat> photos;  // grey, per view
  Eigen::Vector3d Point(double u, double v) const { return origin + u * along + v * down; }
  // The page's corners: texel centres are at integers, so the texture's
  // outer edges (what the photos show) are half a texel outside them.
  std::array<Eigen::Vector3d, 4> Corners() const {
    const double r = texture.cols - 0.5, b = texture.rows - 0.5;
    return {Point(-0.5, -0.5), Point(r, -0.5), Point(r, b), Point(-0.5, b)};
  }
};

// `paint`, when given, changes the page's texture before it is rendered;
// `others`, when given, are the centres of the photos besides the reference.
Scene MakeScene(const std::function<void(cv::Mat1b*)>& paint = nullptr,
                const std::vector<Eigen::Vector3d>& others = {}) {
  Scene s;
  // 0.30 x 0.40 m page at about 1 m, tilted 25 degrees about x; 1 mm texels.
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(25 * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  s.along = tilt * Eigen::Vector3d(0.001, 0, 0);
  s.down = tilt * Eigen::Vector3d(0, 0.001, 0);
  s.texture = cv::Mat1b(400, 300, uchar(235));
  s.origin = Eigen::Vector3d(0, 0, 1.1) - 150 * s.along - 200 * s.down;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> word(6, 22), gap(3, 8), ink(20, 70);
  for (int y = 40; y + 6 < 360; y += 12)  // lines of words, 30 mm margins
    for (int x = 30; x < 270;) {
      const int w = std::min(word(rng), 270 - x);
      cv::rectangle(s.texture, cv::Rect(x, y, w, 6), cv::Scalar(ink(rng)), cv::FILLED);
      x += w + gap(rng);
    }
  if (paint) paint(&s.texture);
  s.cameras.reference = "ref.png";
  s.cameras.views = {LookAt("ref.png", {0, 0, 0}, {0, 0, 1.1}),
                     LookAt("b.png", {0.35, 0.05, 0.05}, {0, 0, 1.1}),
                     LookAt("c.png", {-0.3, 0.1, 0.0}, {0, 0, 1.1}),
                     LookAt("d.png", {0.05, -0.35, 0.1}, {0, 0, 1.1})};
  if (!others.empty()) {
    s.cameras.views.resize(1);
    for (size_t i = 0; i < others.size(); ++i)
      s.cameras.views.push_back(
          LookAt("view_" + std::to_string(i + 1) + ".png", others[i], {0, 0, 1.1}));
  }
  for (const PinholeCamera& c : s.cameras.views) {
    // Texel (u, v) -> pixel through K [R along | R down | R origin + t].
    Eigen::Matrix3d M;
    M.col(0) = c.R * s.along;
    M.col(1) = c.R * s.down;
    M.col(2) = c.R * s.origin + c.t;
    const Eigen::Matrix3d H = c.K * M;
    cv::Mat Hcv(3, 3, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) Hcv.at<double>(r, k) = H(r, k);
    cv::Mat1b photo(c.height, c.width, uchar(70));  // the table
    cv::Mat1b page, cover;
    // The texture's border replicated: the edge is blended with the table
    // once, by `cover`, not darkened by the warp's black border as well
    // (which moved the edge's steepest grey by a view-dependent part of a
    // pixel).
    cv::warpPerspective(s.texture, page, Hcv, photo.size(), cv::INTER_AREA, cv::BORDER_REPLICATE);
    cv::warpPerspective(cv::Mat1b(s.texture.size(), uchar(255)), cover, Hcv, photo.size(),
                        cv::INTER_LINEAR);
    // Blend along the edge as a camera would.
    cv::Mat1f a, p, t;
    cover.convertTo(a, CV_32F, 1 / 255.0);
    page.convertTo(p, CV_32F);
    photo.convertTo(t, CV_32F);
    cv::Mat1f mixed = p.mul(a) + t.mul(1 - a);
    mixed.convertTo(photo, CV_8U);
    s.photos.push_back(photo);
  }
  return s;
}

// Inputs with the cameras and photos of a scene (the first is the reference);
// no boundary, region or points yet.
DensifyInputs PhotoInputs(const CameraSet& cameras, const std::vector<cv::Mat>& photos) {
  DensifyInputs in;
  in.cameras = cameras;
  in.distortion.assign(cameras.views.size(), {0, 0, 0, 0});
  cv::cvtColor(photos[0], in.reference, cv::COLOR_GRAY2BGR);
  in.photos = photos;
  in.photos[0] = cv::Mat();
  return in;
}

DensifyInputs InputsOf(const Scene& s, int sfm_points) {
  DensifyInputs in = PhotoInputs(s.cameras, s.photos);
  const PinholeCamera& ref = s.cameras.views[0];
  const auto corners = s.Corners();
  in.boundary.width = ref.width;
  in.boundary.height = ref.height;
  for (int i = 0; i < 4; ++i) {
    in.boundary.corners[i] = ref.Project(corners[i]);
    in.boundary.contour.push_back(in.boundary.corners[i]);
  }
  for (int i = 0; i < 4; ++i) {
    in.boundary.sides[i].real = true;
    // top TL->TR, right TR->BR, bottom BL->BR, left TL->BL
    const int a = i == 2 ? 3 : i == 3 ? 0 : i, b = i == 2 ? 2 : i == 3 ? 3 : i + 1;
    for (int k = 0; k <= 20; ++k)
      in.boundary.sides[i].points.push_back(
          in.boundary.corners[a] + (in.boundary.corners[b] - in.boundary.corners[a]) * k / 20.0);
  }
  in.region = ContourRegion(in.boundary, 0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(20, 280), v(20, 380);
  for (int i = 0; i < sfm_points; ++i) in.points.vertices.push_back(s.Point(u(rng), v(rng)));
  in.points.colors.assign(in.points.vertices.size(), {128, 128, 128});
  return in;
}

double DistanceToPage(const Scene& s, const Eigen::Vector3d& X) {
  const Eigen::Vector3d n = s.along.cross(s.down).normalized();
  return std::abs(n.dot(X - s.origin));
}

double DistanceToOutline(const Scene& s, const Eigen::Vector3d& X) {
  const auto c = s.Corners();
  double best = 1e9;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d a = c[i], b = c[(i + 1) % 4];
    const double t = std::clamp((X - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    best = std::min(best, (X - (a + t * (b - a))).norm());
  }
  return best;
}

TEST(Densify, PointsLieOnTheRenderedPageAndItsOutline) {
  const Scene scene = MakeScene();
  const DensifyInputs in = InputsOf(scene, 150);
  const DensifyResult r = densify::Run(in, DensifyOptions());
  const double diagonal = 0.5;  // of the 0.3 x 0.4 page
  const auto& source = r.points.FindProperty("source")->values;
  ASSERT_EQ(source.size(), r.points.vertices.size());
  EXPECT_EQ(r.sfm_points, 150);
  std::vector<double> on_page, on_outline;
  for (size_t i = 0; i < r.points.vertices.size(); ++i) {
    if (source[i] == double(PointSource::kTexture))
      on_page.push_back(DistanceToPage(scene, r.points.vertices[i]));
    if (source[i] == double(PointSource::kOutline))
      on_outline.push_back(DistanceToOutline(scene, r.points.vertices[i]));
  }
  ASSERT_EQ(int(on_page.size()), r.texture_points);
  ASSERT_EQ(int(on_outline.size()), r.outline.points);
  auto quantile = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v.empty() ? NAN : v[size_t(q * (v.size() - 1))];
  };
  std::printf(
      "[densify] rendered page: %d texture points (median %.3f %%, p95 %.3f %% of the "
      "diagonal off the page), %d of %d outline samples (median %.3f %%, p95 %.3f %% off "
      "the outline)\n",
      r.texture_points, 100 * quantile(on_page, 0.5) / diagonal,
      100 * quantile(on_page, 0.95) / diagonal, r.outline.points, r.outline.samples,
      100 * quantile(on_outline, 0.5) / diagonal, 100 * quantile(on_outline, 0.95) / diagonal);
  EXPECT_GT(r.texture_points, 2000);
  EXPECT_LT(quantile(on_page, 0.5), 0.0005 * diagonal);
  EXPECT_LT(quantile(on_page, 0.95), 0.002 * diagonal);
  EXPECT_GT(r.outline.points, r.outline.samples / 2);
  EXPECT_LT(quantile(on_outline, 0.5), 0.001 * diagonal);
  EXPECT_LT(quantile(on_outline, 0.95), 0.003 * diagonal);
  // Nothing of the table: every new point is on the page or its edge.
  EXPECT_LT(quantile(on_page, 1.0), 0.01 * diagonal);
  EXPECT_LT(quantile(on_outline, 1.0), 0.01 * diagonal);
}

// A page folded along its middle row: the top half as in MakeScene, the
// bottom half turned 55 degrees about the fold, towards the cameras. sfm's
// points lie on the top half only, so the page's homography fits that half.
struct FoldedScene {
  Eigen::Vector3d origin, along, down, down2;
  double fold = 200;  // texel row of the fold
  cv::Mat1b texture;
  CameraSet cameras;
  std::vector<cv::Mat> photos;
  Eigen::Vector3d Point(double u, double v) const {
    if (v <= fold) return origin + u * along + v * down;
    return origin + u * along + fold * down + (v - fold) * down2;
  }
  double Distance(const Eigen::Vector3d& X) const {
    const Eigen::Vector3d hinge = origin + fold * down;
    const Eigen::Vector3d n1 = along.cross(down).normalized(), n2 = along.cross(down2).normalized();
    // The half whose side of the fold X projects onto.
    return (X - hinge).dot(down) <= 0 ? std::abs(n1.dot(X - hinge)) : std::abs(n2.dot(X - hinge));
  }
};

FoldedScene MakeFoldedScene() {
  const Scene flat = MakeScene();
  FoldedScene s;
  s.origin = flat.origin;
  s.along = flat.along;
  s.down = flat.down;
  s.down2 = Eigen::AngleAxisd(-55 * M_PI / 180, flat.along.normalized()) * flat.down;
  s.texture = flat.texture;
  s.cameras = flat.cameras;
  for (const PinholeCamera& c : s.cameras.views) {
    cv::Mat1f page(c.height, c.width, 0.0f), cover(c.height, c.width, 0.0f);
    for (int half = 0; half < 2; ++half) {
      const int first = half == 0 ? 0 : int(s.fold);
      const cv::Mat1b part = s.texture.rowRange(first, half == 0 ? int(s.fold) : s.texture.rows);
      Eigen::Matrix3d M;
      M.col(0) = c.R * s.along;
      M.col(1) = c.R * (half == 0 ? s.down : s.down2);
      M.col(2) = c.R * s.Point(0, first) + c.t;
      const Eigen::Matrix3d H = c.K * M;
      cv::Mat Hcv(3, 3, CV_64F);
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) Hcv.at<double>(r, k) = H(r, k);
      cv::Mat1f part_f, p, a;
      part.convertTo(part_f, CV_32F);
      cv::warpPerspective(part_f, p, Hcv, page.size(), cv::INTER_AREA);
      cv::warpPerspective(cv::Mat1f(part.size(), 1.0f), a, Hcv, page.size(), cv::INTER_LINEAR);
      page += p.mul(a);
      cover += a;
    }
    cv::min(cover, 1.0f, cover);
    cv::Mat1f mixed = page + 70.0f * (1 - cover);
    cv::Mat1b photo;
    mixed.convertTo(photo, CV_8U);
    s.photos.push_back(photo);
  }
  return s;
}

// The folded page's photos, its outline in the reference, and 150 sfm
// points on its top half.
DensifyInputs FoldedInputs(const FoldedScene& scene) {
  DensifyInputs in = PhotoInputs(scene.cameras, scene.photos);
  const PinholeCamera& ref = scene.cameras.views[0];
  const double r = scene.texture.cols - 0.5, b = scene.texture.rows - 0.5;
  for (const Eigen::Vector3d& X :
       {scene.Point(-0.5, -0.5), scene.Point(r, -0.5), scene.Point(r, scene.fold),
        scene.Point(r, b), scene.Point(-0.5, b), scene.Point(-0.5, scene.fold)})
    in.boundary.contour.push_back(ref.Project(X));
  in.boundary.width = ref.width;
  in.boundary.height = ref.height;
  in.region = ContourRegion(in.boundary, 0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(20, 280), v(20, 190);
  for (int i = 0; i < 150; ++i) in.points.vertices.push_back(scene.Point(u(rng), v(rng)));
  in.points.colors.assign(in.points.vertices.size(), {128, 128, 128});
  return in;
}

// The points of `source` in `result`: their distances to the folded page
// appended to `errors`; returns how many lie 20 mm or more past the fold.
int PastTheFold(const FoldedScene& scene, const DensifyResult& result, PointSource source,
                std::vector<double>* errors) {
  const auto& sources = result.points.FindProperty("source")->values;
  const Eigen::Vector3d hinge = scene.Point(0, scene.fold);
  int n = 0;
  for (size_t i = 0; i < result.points.vertices.size(); ++i) {
    if (sources[i] != double(source)) continue;
    const Eigen::Vector3d& X = result.points.vertices[i];
    errors->push_back(scene.Distance(X));
    if ((X - hinge).dot(scene.down2.normalized()) > 0.02) ++n;
  }
  return n;
}

TEST(Densify, TheFarSideOfAFoldGetsPointsThroughTheSurfaceOfTheFirst) {
  const FoldedScene scene = MakeFoldedScene();
  const DensifyInputs in = FoldedInputs(scene);

  DensifyOptions o;
  o.outline.enabled = false;
  o.texture.surface_prewarp = false;
  std::vector<double> errors_first;  // (filled, not checked)
  const DensifyResult first = densify::Run(in, o);
  const int far_first = PastTheFold(scene, first, PointSource::kTexture, &errors_first);
  o.texture.surface_prewarp = true;
  // Every sample it left: this page is small (300x400 texels), its far side
  // lies within the default hole gap of the points past the fold.
  o.texture.surface_hole_px = 0;
  std::vector<double> errors;
  const DensifyResult both = densify::Run(in, o);
  const int far_both = PastTheFold(scene, both, PointSource::kTexture, &errors);
  std::sort(errors.begin(), errors.end());
  const double diagonal = 0.5;
  std::printf(
      "[densify] folded page: %d texture points past the fold with the page's "
      "homography, %d with the second pass (%d points in all; median %.3f %%, p95 "
      "%.3f %% of the diagonal off the page)\n",
      far_first, far_both, both.texture_points, 100 * errors[errors.size() / 2] / diagonal,
      100 * errors[errors.size() * 95 / 100] / diagonal);
  EXPECT_EQ(first.texture_points_surface, 0);
  EXPECT_EQ(both.texture_points_surface, both.texture_points - first.texture_points);
  EXPECT_GT(far_both, far_first + 500);
  EXPECT_LT(errors[errors.size() / 2], 0.0005 * diagonal);
  EXPECT_LT(errors[errors.size() * 95 / 100], 0.002 * diagonal);
  // A few next to the fold, where the photos blend the two halves, are off
  // by more (the first pass has them too: its largest 1 % of the diagonal).
  EXPECT_LT(errors[errors.size() * 99 / 100], 0.005 * diagonal);
  EXPECT_LT(errors.back(), 0.02 * diagonal);
}

// With only sfm's points on the top half, the sweep carries the reference's
// patches into the other photos through the surface of the points so far and
// reaches the far side of the fold round by round, on the page.
TEST(Densify, SweptPointsReachTheFarSideOfAFoldOnThePage) {
  const FoldedScene scene = MakeFoldedScene();
  const DensifyInputs in = FoldedInputs(scene);

  DensifyOptions o;
  o.texture.enabled = o.outline.enabled = o.steps.enabled = false;
  const DensifyResult result = densify::Run(in, o);
  std::vector<double> errors;
  const int far = PastTheFold(scene, result, PointSource::kSwept, &errors);
  ASSERT_FALSE(errors.empty());
  std::sort(errors.begin(), errors.end());
  const double diagonal = 0.5;
  std::printf(
      "[densify] folded page, sweep only: %d swept points (%d past the fold) from %d "
      "candidates; median %.3f %%, p95 %.3f %%, max %.3f %% of the diagonal off the page\n",
      result.sweep.points, far, result.sweep.candidates, 100 * errors[errors.size() / 2] / diagonal,
      100 * errors[errors.size() * 95 / 100] / diagonal, 100 * errors.back() / diagonal);
  // Measured: 1605 points, 1186 past the fold; median 0.16 %, p95 0.46 %, max
  // 0.56 % of the diagonal. The depth is one of 81 steps over +-15 %, 0.4 %
  // of the depth apart, with nothing finer between them. Where the flow
  // reaches, its points are far more exact (0.006 %, the test above).
  EXPECT_EQ(int(errors.size()), result.sweep.points);
  EXPECT_GT(far, 800);
  EXPECT_LT(errors[errors.size() / 2], 0.0025 * diagonal);
  EXPECT_LT(errors[errors.size() * 95 / 100], 0.006 * diagonal);
  EXPECT_LT(errors.back(), 0.01 * diagonal);
}

// A step in the grey of blank paper (as a fold's shading gives under diffuse
// light: at the same place on the paper in every photo) gets points, on the
// page and on the step.
TEST(Densify, ShadingStepsOfBlankPaperGetPointsOnThePage) {
  const Scene scene = MakeScene([](cv::Mat1b* texture) {
    // The lower third blank, darker right of a diagonal (x - 80 = y - 260),
    // which crosses every photo's epipolar lines.
    (*texture)(cv::Rect(0, 260, 300, 140)).setTo(235);
    for (int y = 260; y < 400; ++y)
      for (int x = 80 + (y - 260); x < 300; ++x) (*texture)(y, x) = 195;
  });
  // Few sfm points, as on blank paper: the step is far from all of them.
  const DensifyInputs in = InputsOf(scene, 20);
  DensifyOptions o;
  const DensifyResult r = densify::Run(in, o);
  ASSERT_GT(r.steps.samples, 0);
  ASSERT_GT(r.steps.points, 5) << r.steps.samples << " samples, " << r.steps.unmatched
                               << " unmatched, " << r.steps.off_surface << " off the surface";
  const std::vector<double>& source = r.points.properties[2].values;
  const Eigen::Vector3d n = scene.along.cross(scene.down).normalized();
  for (size_t i = 0; i < r.points.vertices.size(); ++i) {
    if (source[i] != double(PointSource::kStep)) continue;
    const Eigen::Vector3d& X = r.points.vertices[i];
    // Measured up to 1.6 mm (0.3 % of the diagonal): a step blurred by 3 px
    // is found less exactly than print.
    EXPECT_LT(DistanceToPage(scene, X), 0.0025);
    // On the step (texel coordinates u along the page, v down it).
    const Eigen::Vector3d d = X - scene.origin;
    const double u = d.dot(scene.along) / scene.along.squaredNorm();
    const double v = (d - d.dot(n) * n).dot(scene.down) / scene.down.squaredNorm();
    EXPECT_NEAR(u - 80 + 0.5, v - 260, 3.0);
    EXPECT_GT(v, 255);
  }
  o.steps.enabled = false;
  EXPECT_EQ(densify::Run(in, o).steps.points, 0);
}

// Photos whose epipolar lines run within a few degrees of the page's top
// side (all of them taken from the side of the page, as of a standing end
// seen from above): no sample there crosses an edge steeply enough to be
// matched, but the side's straight image in each photo places it.
TEST(Densify, ASideEveryPhotoSeesAlongItsEpipolarLinesIsPlacedByItsLines) {
  const Scene scene = MakeScene(nullptr, {{0.35, 0.14, 0.0}, {-0.35, 0.16, 0.05}});
  const DensifyInputs in = InputsOf(scene, 150);
  DensifyOptions o;
  o.texture.enabled = false;
  o.sweep.enabled = false;
  const DensifyResult r = densify::Run(in, o);
  const auto& source = r.points.FindProperty("source")->values;
  const PinholeCamera& ref = scene.cameras.views[0];
  const double top = ref.Project(scene.Corners()[0]).y();
  std::vector<double> top_errors;
  for (size_t i = 0; i < r.points.vertices.size(); ++i) {
    if (source[i] != double(PointSource::kOutline)) continue;
    const Eigen::Vector3d& X = r.points.vertices[i];
    if (std::abs(ref.Project(X).y() - top) < 5) top_errors.push_back(DistanceToOutline(scene, X));
  }
  std::sort(top_errors.begin(), top_errors.end());
  const double diagonal = 0.5;
  std::printf(
      "[densify] side lines: %d of %d outline points from them (%d too weakly placed); %zu "
      "on the top side, median %.3f %%, worst %.3f %% of the diagonal off the outline\n",
      r.outline.side_line_points, r.outline.points, r.outline.side_line_weak, top_errors.size(),
      top_errors.empty() ? NAN : 100 * top_errors[top_errors.size() / 2] / diagonal,
      top_errors.empty() ? NAN : 100 * top_errors.back() / diagonal);
  EXPECT_GE(r.outline.side_line_points, 40);
  EXPECT_GE(int(top_errors.size()), 40);
  ASSERT_FALSE(top_errors.empty());
  // Photos 2 degrees farther up, whose crossings the matching takes, put
  // the side's points 0.28 % (median) and 0.49 % (worst) off the outline.
  EXPECT_LT(top_errors[top_errors.size() / 2], 0.005 * diagonal);
  EXPECT_LT(top_errors.back(), 0.006 * diagonal);
  // Without the sides' lines the top side gets no point.
  o.outline.side_lines = false;
  const DensifyResult without = densify::Run(in, o);
  EXPECT_EQ(without.outline.side_line_points, 0);
  EXPECT_EQ(without.outline.points, r.outline.points - r.outline.side_line_points);
  // MakeScene's own photos see the top side along planes only 3-5 degrees
  // off the reference's: half a pixel in their lines would move a point 0.5 %
  // of its depth, so none is placed.
  o.outline.side_lines = true;
  const DensifyResult weak = densify::Run(InputsOf(MakeScene(), 150), o);
  EXPECT_EQ(weak.outline.side_line_points, 0);
  EXPECT_GE(weak.outline.side_line_weak, 40);
}

TEST(Densify, EachSourceCanBeSwitchedOffAndOneViewAddsNothing) {
  const Scene scene = MakeScene();
  DensifyInputs in = InputsOf(scene, 150);
  DensifyOptions o;
  o.texture.enabled = false;
  DensifyResult r = densify::Run(in, o);
  EXPECT_EQ(r.texture_points, 0);
  EXPECT_GT(r.outline.points, 0);
  o.texture.enabled = true;
  o.outline.enabled = false;
  r = densify::Run(in, o);
  EXPECT_GT(r.texture_points, 0);
  EXPECT_EQ(r.outline.points, 0);
  o.sweep.enabled = false;
  r = densify::Run(in, o);
  EXPECT_EQ(r.sweep.points + r.sweep.candidates, 0);
  // Only the reference view: sfm's points come back unchanged, with a warning.
  in.cameras.views.resize(1);
  in.photos.resize(1);
  in.distortion.resize(1);
  r = densify::Run(in, DensifyOptions());
  EXPECT_EQ(r.points.vertices.size(), 150u);
  EXPECT_EQ(r.texture_points + r.outline.points + r.sweep.points, 0);
  EXPECT_FALSE(r.warnings.empty());
}

}  // namespace
}  // namespace docunfold::testing
