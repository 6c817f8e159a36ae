// segment-boundary on drawn scenes whose truth is known exactly: a page on a
// plain and on a textured table, a page cut off by the image border, an empty
// table; and the corner and orientation helpers.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "common/errors.h"
#include "common/page_files.h"
#include "stages/segment-boundary/segment_boundary.h"

namespace docunfold::boundary {
namespace {

struct Scene {
  cv::Mat3b image;
  cv::Mat1b mask;                    // true page region
  std::vector<cv::Point2d> corners;  // true corners, clockwise
};

// A table (plain green with noise, or a blotchy texture) with a white page
// (quadrilateral `corners`) carrying lines of dark "text" blocks.
Scene DrawScene(const std::vector<cv::Point2d>& corners, bool textured,
                cv::Size size = {1200, 900}) {
  Scene s;
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0, 3);
  s.image = cv::Mat3b(size, cv::Vec3b(70, 110, 60));
  if (textured) {
    std::uniform_int_distribution<int> x(0, size.width), y(0, size.height), r(3, 12), c(-35, 35);
    for (int i = 0; i < 6000; ++i) {
      const int d = c(rng);
      cv::circle(s.image, {x(rng), y(rng)}, r(rng), cv::Scalar(70 + d, 110 + d, 60 + d), cv::FILLED,
                 cv::LINE_AA);
    }
  }
  std::vector<cv::Point> poly;
  for (const auto& p : corners) poly.emplace_back(int(std::lround(p.x)), int(std::lround(p.y)));
  s.mask = cv::Mat1b::zeros(size);
  cv::fillConvexPoly(s.mask, poly, 255);
  s.image.setTo(cv::Scalar(235, 238, 240), s.mask);
  // Text blocks along the page's top side direction.
  const cv::Point2d u = (corners[1] - corners[0]) * (1.0 / cv::norm(corners[1] - corners[0]));
  const cv::Point2d v = (corners[3] - corners[0]) * (1.0 / cv::norm(corners[3] - corners[0]));
  const double w = cv::norm(corners[1] - corners[0]), h = cv::norm(corners[3] - corners[0]);
  for (double t = 0.1 * h; t < 0.9 * h; t += 14)
    for (double a = 0.1 * w; a < 0.85 * w; a += 9) {
      const cv::Point2d p = corners[0] + u * a + v * t;
      cv::line(s.image, p, p + v * 6.0, cv::Scalar(40, 40, 40), 2, cv::LINE_AA);
    }
  s.image.forEach([&](cv::Vec3b& px, const int*) {
    for (int c = 0; c < 3; ++c) px[c] = cv::saturate_cast<uchar>(px[c] + noise(rng));
  });
  s.corners = corners;
  return s;
}

double Iou(const cv::Mat1b& a, const cv::Mat1b& b) {
  return double(cv::countNonZero(a & b)) / cv::countNonZero(a | b);
}

double NearestCorner(const BoundaryResult& r, const cv::Point2d& p) {
  double best = 1e300;
  for (const auto& c : r.corners) best = std::min(best, cv::norm(c - p));
  return best;
}

double SignedArea(const std::array<cv::Point2d, 4>& c) {
  double a = 0;
  for (int i = 0; i < 4; ++i) a += c[i].x * c[(i + 1) % 4].y - c[(i + 1) % 4].x * c[i].y;
  return 0.5 * a;
}

const std::vector<cv::Point2d> kTilted = {{380, 140}, {820, 210}, {760, 780}, {300, 700}};

TEST(SegmentBoundary, FindsAPageOnAPlainTable) {
  const Scene s = DrawScene(kTilted, false);
  const BoundaryResult r = SegmentBoundary(s.image, {});
  EXPECT_GE(Iou(r.mask, s.mask), 0.99);
  for (const auto& c : s.corners) EXPECT_LE(NearestCorner(r, c), 3.0) << c;
  for (const Side& side : r.sides) EXPECT_TRUE(side.real);
  EXPECT_GT(SignedArea(r.corners), 0) << "corners must run clockwise in the image";
  // Sides share the corners: top TL->TR, right TR->BR, bottom BL->BR, left TL->BL.
  EXPECT_LE(cv::norm(r.sides[kTop].points.front() - r.corners[0]), 1e-9);
  EXPECT_LE(cv::norm(r.sides[kTop].points.back() - r.corners[1]), 1e-9);
  EXPECT_LE(cv::norm(r.sides[kRight].points.back() - r.corners[2]), 1e-9);
  EXPECT_LE(cv::norm(r.sides[kBottom].points.front() - r.corners[3]), 1e-9);
  EXPECT_LE(cv::norm(r.sides[kLeft].points.back() - r.corners[3]), 1e-9);
  EXPECT_TRUE(r.folded_corners.empty());
}

TEST(SegmentBoundary, AFoldedCornerIsCompletedPastTheFold) {
  // kTilted with its top-right corner folded under: the triangle between the
  // corner and a fold from 70 % along the top side to 30 % down the right
  // side shows the table.
  Scene s = DrawScene(kTilted, false);
  const cv::Point2d corner = kTilted[1];
  const cv::Point2d fold_top = kTilted[0] + 0.7 * (kTilted[1] - kTilted[0]);
  const cv::Point2d fold_right = kTilted[1] + 0.3 * (kTilted[2] - kTilted[1]);
  const std::vector<cv::Point> gone = {corner, fold_top, fold_right};
  cv::fillConvexPoly(s.image, gone, cv::Scalar(70, 110, 60));
  cv::fillConvexPoly(s.mask, gone, cv::Scalar(0));
  BoundaryOptions opt;
  opt.orientation = OrientationSource::kGeometry;
  const BoundaryResult r = SegmentBoundary(s.image, opt);
  EXPECT_GE(Iou(r.mask, s.mask), 0.98);
  ASSERT_EQ(r.folded_corners.size(), 1u);
  EXPECT_EQ(r.folded_corners[0].corner, 1);  // TR
  EXPECT_LE(cv::norm(r.corners[1] - corner), 4.0) << r.corners[1];
  for (int i : {0, 2, 3}) EXPECT_LE(cv::norm(r.corners[i] - kTilted[i]), 3.0) << i;
  const std::array<cv::Point2d, 2>& fold = r.folded_corners[0].fold;
  EXPECT_LE(std::min(cv::norm(fold[0] - fold_top) + cv::norm(fold[1] - fold_right),
                     cv::norm(fold[0] - fold_right) + cv::norm(fold[1] - fold_top)),
            10.0);
  // Both sides run on to the corner and stay real (straightened downstream).
  EXPECT_TRUE(r.sides[kTop].real && r.sides[kRight].real);
  EXPECT_LE(cv::norm(r.sides[kTop].points.back() - r.corners[1]), 1e-9);
  EXPECT_LE(cv::norm(r.sides[kRight].points.front() - r.corners[1]), 1e-9);
  // boundary.json names it, and the reader gives the triangle with no page.
  const Boundary b =
      ParseBoundary(BoundaryToJson(r, "reference.png", s.image.cols, s.image.rows, Json::object()),
                    "boundary.json");
  ASSERT_EQ(b.folded_away.size(), 1u);
  EXPECT_LE((b.folded_away[0][0] - Eigen::Vector2d(corner.x, corner.y)).norm(), 4.0);
}

TEST(SegmentBoundary, FindsAPageOnATexturedTable) {
  const Scene s = DrawScene(kTilted, true);
  const BoundaryResult r = SegmentBoundary(s.image, {});
  EXPECT_GE(Iou(r.mask, s.mask), 0.98);
  for (const auto& c : s.corners) EXPECT_LE(NearestCorner(r, c), 4.0) << c;
}

TEST(SegmentBoundary, GeometricOrientationPutsTheUpwardSideOnTop) {
  const Scene s = DrawScene(kTilted, false);
  BoundaryOptions opt;
  opt.orientation = OrientationSource::kGeometry;
  const BoundaryResult r = SegmentBoundary(s.image, opt);
  EXPECT_EQ(r.orientation.method, "geometry");
  EXPECT_LE(cv::norm(r.corners[0] - kTilted[0]), 3.0);  // (380, 140) starts the top side
}

TEST(SegmentBoundary, CutOffPageHasItsCutSideNotReal) {
  // The page runs off the bottom of the image.
  const Scene s = DrawScene({{350, 300}, {850, 320}, {840, 1100}, {340, 1080}}, true);
  BoundaryOptions opt;
  opt.orientation = OrientationSource::kGeometry;
  const BoundaryResult r = SegmentBoundary(s.image, opt);
  EXPECT_GE(Iou(r.mask, s.mask), 0.98);
  EXPECT_TRUE(r.sides[kTop].real);
  EXPECT_TRUE(r.sides[kLeft].real);
  EXPECT_TRUE(r.sides[kRight].real);
  EXPECT_FALSE(r.sides[kBottom].real);
  EXPECT_TRUE(r.corner_in_image[0] && r.corner_in_image[1]);
  EXPECT_FALSE(r.corner_in_image[2] || r.corner_in_image[3]);
  // The real parts of the sides may end at the image border but never run
  // along it.
  for (const Side& side : r.sides)
    for (const auto& part : side.real_parts)
      for (size_t k = 1; k < part.size(); ++k)
        EXPECT_FALSE(part[k - 1].y >= s.image.rows - 3 && part[k].y >= s.image.rows - 3);
}

TEST(SegmentBoundary, EmptyTableIsNoDocument) {
  Scene s = DrawScene(kTilted, true);
  s.image = DrawScene({{-10, -10}, {-5, -10}, {-5, -5}, {-10, -5}}, true).image;
  try {
    SegmentBoundary(s.image, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no document found"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SegmentBoundary(cv::Mat3b(600, 800, cv::Vec3b(128, 128, 128)), {}), InputError);
  // A page that fills the image (as a scanner app saves it): the message says
  // what may be wrong.
  cv::Mat3b scan(800, 600, cv::Vec3b(236, 240, 242));
  for (int y = 60; y < 760; y += 24)
    cv::line(scan, {50, y}, {550 - (y * 7) % 200, y}, cv::Scalar(40, 40, 40), 3);
  try {
    SegmentBoundary(scan, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fill the photo with no table around it"),
              std::string::npos)
        << e.what();
  }
}

// The outline through `vertices` and back to the first, one point per pixel
// step along the longer axis of each edge (as findContours gives it).
std::vector<cv::Point> ClosedOutline(const std::vector<cv::Point>& vertices) {
  std::vector<cv::Point> contour;
  for (size_t i = 0; i < vertices.size(); ++i) {
    const cv::Point a = vertices[i], b = vertices[(i + 1) % vertices.size()];
    const int n = std::max(std::abs(b.x - a.x), std::abs(b.y - a.y));
    for (int k = 0; k < n; ++k) contour.emplace_back(a + (b - a) * (double(k) / n));
  }
  return contour;
}

TEST(CornerHelpers, FourSharpestTurnsWinOverAFoldKink) {
  // A clockwise square with a shallow kink (a fold) in its top side.
  const std::vector<cv::Point> contour =
      ClosedOutline({{0, 0}, {200, -25}, {400, 0}, {400, 400}, {0, 400}});
  const auto idx = detail::FindCornerIndices(contour);
  const std::vector<cv::Point> expected = {{0, 0}, {400, 0}, {400, 400}, {0, 400}};
  for (int i = 0; i < 4; ++i) EXPECT_LE(cv::norm(contour[idx[i]] - expected[i]), 2.0) << i;
}

// The outline of a page whose top panel is folded up and seen foreshortened
// (as in samples/set01): a hexagon whose fold kinks turn more sharply than
// the panel's own corners.
std::vector<cv::Point> FoldedPageOutline() {
  // The folded panel's top side, the right side's panel part, the right side
  // below the fold kink, the bottom, the left side below the kink and the
  // left side's panel part.
  return ClosedOutline({{220, 60}, {480, 60}, {600, 140}, {600, 500}, {100, 500}, {100, 140}});
}

TEST(CornerHelpers, FoldKinksAreNotCornersWhenTheFoldIsSeen) {
  const std::vector<cv::Point> contour = FoldedPageOutline();
  const auto near = [](const cv::Point& p, const cv::Point& q) { return cv::norm(p - q) <= 3; };
  const detail::FoldTest fold = [&](const cv::Point& a, const cv::Point& b) {
    return (near(a, {100, 140}) && near(b, {600, 140})) ||
           (near(b, {100, 140}) && near(a, {600, 140}));
  };
  const std::vector<cv::Point> expected = {{220, 60}, {480, 60}, {600, 500}, {100, 500}};
  // From the outline alone the kinks win: the case the fold test is for.
  const auto blind = detail::FindCornerIndices(contour);
  int kinks = 0;
  for (int i = 0; i < 4; ++i)
    kinks += near(contour[blind[i]], {100, 140}) || near(contour[blind[i]], {600, 140});
  EXPECT_GT(kinks, 0);
  const auto idx = detail::FindCornerIndices(contour, fold);
  for (int i = 0; i < 4; ++i)
    EXPECT_LE(cv::norm(contour[idx[i]] - expected[i]), 3.0) << i << " " << contour[idx[i]];
}

TEST(CornerHelpers, ASideAlongAShadedFlapIsNoFold) {
  // Page corners (100,100) (600,100) (600,500) (100,500); the left side
  // bulges out over a flap (kinks of 27 degrees at (40,220) and (40,380),
  // 8 % of the area) whose shading differs, so the shading test calls the
  // chord between the two left corners a fold (set05's reference view).
  const std::vector<cv::Point> contour =
      ClosedOutline({{100, 100}, {600, 100}, {600, 500}, {100, 500}, {40, 380}, {40, 220}});
  const auto near = [](const cv::Point& p, const cv::Point& q) { return cv::norm(p - q) <= 3; };
  const detail::FoldTest shaded_chord = [&](const cv::Point& a, const cv::Point& b) {
    return (near(a, {100, 100}) && near(b, {100, 500})) ||
           (near(b, {100, 100}) && near(a, {100, 500}));
  };
  const std::vector<cv::Point> expected = {{100, 100}, {600, 100}, {600, 500}, {100, 500}};
  const auto idx = detail::FindCornerIndices(contour, shaded_chord);
  for (int i = 0; i < 4; ++i)
    EXPECT_LE(cv::norm(contour[idx[i]] - expected[i]), 3.0) << i << " " << contour[idx[i]];
}

// A page cut off by the image's bottom border (y = 399) as in set08's
// reference view: its bottom-left corner (100,330) lies in the image, but the
// outline turns more where its bottom side leaves the image at (150,399),
// 20 % of the way from there to the top-left corner.
std::vector<cv::Point> PageLeavingTheImage(const cv::Point& bottom_left) {
  // The right side leaves the image at (600,399); the outline runs along the
  // image border to (150,399).
  return ClosedOutline({{130, 60}, {560, 80}, {600, 399}, {150, 399}, bottom_left});
}

TEST(CornerHelpers, APageCornerNearWhereItsSideLeavesTheImageIsTheCorner) {
  const auto on_border = [](const cv::Point& p) { return p.y >= 397; };
  const std::vector<cv::Point> contour = PageLeavingTheImage({100, 330});
  const auto found = detail::FindCornerIndices(contour);
  // The outline alone picks the border exit...
  int exits = 0;
  for (int i = 0; i < 4; ++i) exits += cv::norm(contour[found[i]] - cv::Point(150, 399)) <= 3;
  ASSERT_EQ(exits, 1);
  // ...and the page corner up the side replaces it; the exit of the
  // right side, with no turn before it, stays.
  const auto moved = detail::MoveBorderCornersToPageCorners(contour, found, on_border);
  const std::vector<cv::Point> expected = {{130, 60}, {560, 80}, {600, 399}, {100, 330}};
  for (int i = 0; i < 4; ++i)
    EXPECT_LE(cv::norm(contour[moved[i]] - expected[i]), 3.0) << i << " " << contour[moved[i]];
  // A straight side into the border keeps its exit as the corner.
  const std::vector<cv::Point> straight = PageLeavingTheImage({145, 314});
  const auto kept = detail::FindCornerIndices(straight);
  EXPECT_EQ(detail::MoveBorderCornersToPageCorners(straight, kept, on_border), kept);
  // Nor does a corner in the image move.
  const auto nowhere = [](const cv::Point&) { return false; };
  EXPECT_EQ(detail::MoveBorderCornersToPageCorners(contour, found, nowhere), found);
}

// A page whose top-left corner (250,153) lies 73 px past the end (300,100)
// of a fold's crease that meets its top side, as in set08's reference view:
// the crease's end turns 45 degrees, the corner 38.
std::vector<cv::Point> PageWithACreaseNextToACorner() {
  return ClosedOutline({{300, 100}, {850, 80}, {820, 720}, {200, 700}, {250, 153}});
}

TEST(CornerHelpers, ACreaseEndNextToACornerGivesWayToIt) {
  const std::vector<cv::Point> contour = PageWithACreaseNextToACorner();
  const auto near = [](const cv::Point& p, const cv::Point& q) { return cv::norm(p - q) <= 3; };
  const auto nowhere = [](const cv::Point&) { return false; };
  const auto found = detail::FindCornerIndices(contour);
  int at_crease = 0;
  for (int i = 0; i < 4; ++i) at_crease += near(contour[found[i]], {300, 100});
  ASSERT_EQ(at_crease, 1) << "the outline's turning alone should take the crease's end";
  // A crease runs from the crease's end across the page: the corner moves.
  const detail::FoldTest crease = [&](const cv::Point& a, const cv::Point&) {
    return near(a, {300, 100});
  };
  const auto moved = detail::MoveFoldEndsToPageCorners(contour, found, nowhere, crease);
  const std::vector<cv::Point> expected = {{250, 153}, {850, 80}, {820, 720}, {200, 700}};
  for (int i = 0; i < 4; ++i) {
    double nearest = 1e9;
    for (const auto& e : expected) nearest = std::min(nearest, cv::norm(contour[moved[i]] - e));
    EXPECT_LE(nearest, 4.0) << i << " " << contour[moved[i]];
  }
  // No crease, or one from the turn beside it too (then the corner found may
  // be the page's and the turn the crease's end): nothing moves.
  const detail::FoldTest none = [](const cv::Point&, const cv::Point&) { return false; };
  EXPECT_EQ(detail::MoveFoldEndsToPageCorners(contour, found, nowhere, none), found);
  const detail::FoldTest both = [&](const cv::Point& a, const cv::Point&) {
    return near(a, {300, 100}) || cv::norm(a - cv::Point(250, 153)) <= 12;
  };
  EXPECT_EQ(detail::MoveFoldEndsToPageCorners(contour, found, nowhere, both), found);
}

TEST(CornerHelpers, ShadingStepTellsAFoldFromAFlatPageAndASide) {
  // The folded page of FoldedPageOutline: panel above y = 140 darker.
  cv::Mat1b mask = cv::Mat1b::zeros(560, 700);
  std::vector<cv::Point> outline = FoldedPageOutline();
  cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{outline}, 255);
  cv::Mat1f grey(mask.size(), 60.0f);
  grey.setTo(210.0f, mask);
  grey(cv::Rect(0, 0, 700, 140)).setTo(150.0f, mask(cv::Rect(0, 0, 700, 140)));
  EXPECT_TRUE(detail::IsShadingStep(grey, mask, 1.0, {100, 140}, {600, 140}));
  EXPECT_FALSE(detail::IsShadingStep(grey, mask, 1.0, {100, 300}, {600, 300}));  // flat
  EXPECT_FALSE(detail::IsShadingStep(grey, mask, 1.0, {600, 500}, {100, 500}));  // a side
  EXPECT_FALSE(detail::IsShadingStep(grey, mask, 1.0, {100, 500}, {480, 60}));   // crosses it
  // Full-resolution points on a half-size image.
  cv::Mat1f grey_half;
  cv::Mat1b mask_half;
  cv::resize(grey, grey_half, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  cv::resize(mask, mask_half, cv::Size(), 0.5, 0.5, cv::INTER_NEAREST);
  EXPECT_TRUE(detail::IsShadingStep(grey_half, mask_half, 0.5, {100, 140}, {600, 140}));
}

TEST(CornerHelpers, RefinedCornerIsWhereTheSidesMeet) {
  // A square whose corners the mask rounded off (radius 12 px).
  cv::Mat1b mask = cv::Mat1b::zeros(400, 400);
  cv::rectangle(mask, cv::Rect(50, 50, 300, 300), 255, cv::FILLED);
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(25, 25));
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN, kernel);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  ASSERT_EQ(contours.size(), 1u);
  std::vector<cv::Point> contour = contours[0];
  const int reach = std::max(2, int(0.025 * contour.size()));
  const auto idx = detail::FindCornerIndices(contour);
  const std::vector<cv::Point2d> truth = {{50, 50}, {349, 50}, {349, 349}, {50, 349}};
  for (int i = 0; i < 4; ++i) {
    const cv::Point2d refined = detail::RefineCorner(contour, idx[i], reach);
    double nearest = 1e9, before = 1e9;
    for (const auto& t : truth) {
      nearest = std::min(nearest, cv::norm(refined - t));
      before = std::min(before, cv::norm(cv::Point2d(contour[idx[i]]) - t));
    }
    EXPECT_LE(nearest, 1.5) << i;
    EXPECT_GT(before, 3.0) << i << ": the rounding should have moved the outline's turn";
  }
}

TEST(CornerHelpers, TopSideIsTheOneFacingUp) {
  // Clockwise corners of a square turned by 30 degrees.
  std::array<cv::Point2d, 4> c;
  for (int i = 0; i < 4; ++i) {
    const double a = (30 + 90 * i - 135) * CV_PI / 180;
    c[i] = {500 + 100 * std::cos(a), 500 + 100 * std::sin(a)};
  }
  const int top = detail::GeometricTopSide(c);
  const cv::Point2d mid = 0.5 * (c[top] + c[(top + 1) % 4]);
  for (int i = 0; i < 4; ++i) EXPECT_LE(mid.y, 0.5 * (c[i].y + c[(i + 1) % 4].y) + 1e-9);
}

}  // namespace
}  // namespace docunfold::boundary
