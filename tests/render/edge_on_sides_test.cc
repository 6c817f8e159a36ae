// A page side the reference photo sees edge-on is placed from the photo that
// sees it squarely (view_sides.h): a page whose right half curls through a
// quarter turn towards the reference camera, and an M whose curl lies a
// little too far out.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "common/raster.h"
#include "stages/render/crop.h"
#include "stages/render/render.h"
#include "stages/render/view_sides.h"
#include "tests/render/render_fixtures.h"

namespace docunfold::testing {
namespace {

constexpr double kPageW = 0.42, kPageH = 0.56, kHalf = kPageW / 2;

// The page of MakeScene's geometry (the reference camera at the origin
// looking down +z, the page at `origin` tilted 20° about x), its right half
// bent into a cylinder of `radius`; M' runs `past` beyond the page's right
// edge, along the same curl. `drift` moves the curl outwards (along x), by
// that much at the page's edge and by the square of the way there before it.
MeshPair CurledPage(double radius, double past, double drift = 0) {
  const Eigen::Vector3d origin(-0.22, -0.3, 1.0);
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(20 * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  MeshPair m;
  const int nx = 61, ny = 57;
  m.grid = {nx, ny};
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      const double a = (kPageW + past) * c / (nx - 1), b = kPageH * r / (ny - 1);
      Eigen::Vector3d local(a, b, 0);
      if (a > kHalf) {
        const double theta = (a - kHalf) / radius;
        const double way = (a - kHalf) / kHalf;
        local = {kHalf + radius * std::sin(theta) + drift * way * way, b,
                 -radius * (1 - std::cos(theta))};
      }
      m.mesh3d.push_back(origin + tilt * local);
      m.mesh2d.emplace_back(a, b);
    }
  return m;
}

// A camera at `center` looking at `target`, image y along the world's +y.
PinholeCamera LookingAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target) {
  PinholeCamera c;
  c.image = "view_01.png";
  c.width = 640;
  c.height = 480;
  c.K << 500, 0, 319.5, 0, 500, 239.5, 0, 0, 1;
  const Eigen::Vector3d forward = (target - center).normalized();
  const Eigen::Vector3d right = Eigen::Vector3d::UnitY().cross(forward).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  c.R.row(0) = right;
  c.R.row(1) = down;
  c.R.row(2) = forward;
  c.t = -c.R * center;
  return c;
}

// The reference side i's samples on M', and its line.
render::SideFit ReferenceSide(const MeshPair& mesh, const PinholeCamera& camera,
                              const PixelToSurface& lookup, const Boundary& boundary, int i) {
  int samples = 0;
  const auto flat =
      render::MapPolylineOntoFlat(mesh, camera, lookup, boundary.sides[i].points, 0, &samples);
  return render::FitSideLine(i, true, flat, samples);
}

// The curl turns through 90° (radius = half the page / (pi/2)).
constexpr double kRadius = kHalf / (M_PI / 2);

// MakeScene's photo and outline of the true curled page.
SyntheticScene CurledScene() {
  SceneOptions o;
  o.page_w = kPageW;
  o.page_h = kPageH;
  o.radius = kRadius;
  return MakeScene(o);
}

// A photo that looks at the curled end, whose print faces the page's left
// half, from above that half; its mask is where `page` covers its pixels.
render::ViewMask EndOnView(const MeshPair& page) {
  const MeshPair truth = CurledPage(kRadius, 0);
  const Eigen::Vector3d end = truth.mesh3d[truth.grid.Index(28, 60)];
  render::ViewMask view;
  view.camera = LookingAt(end + Eigen::Vector3d(-0.7, 0, -0.35), end);
  view.mask = RasterizeMesh(view.camera, page.mesh3d, page.grid.Triangles()).face >= 0;
  return view;
}

TEST(RenderEdgeOnSides, ASideTheReferenceSeesEdgeOnIsPlacedFromAPhotoThatSeesItSquarely) {
  const MeshPair truth = CurledPage(kRadius, 0);
  const SyntheticScene scene = CurledScene();
  ASSERT_TRUE(scene.real[1]);
  render::RenderInputs in = InputsOf(scene);
  // M: the curl 2 mm (of a 420 mm page) too far out at the edge, running 5 %
  // of the page past it.
  in.meshes = CurledPage(kRadius, 0.05 * kPageW, 0.002);

  const Eigen::Vector3d end = truth.mesh3d[truth.grid.Index(28, 60)];
  const render::ViewMask view = EndOnView(truth);
  ASSERT_GT(cv::countNonZero(view.mask), 10000);
  in.views = {view};

  const PixelToSurface lookup(in.meshes, in.camera);
  const double flat_diagonal = std::hypot(1.05 * kPageW, kPageH);  // M' spans this
  std::array<render::SideFit, 4> sides;
  for (int i = 0; i < 4; ++i)
    sides[i] = ReferenceSide(in.meshes, in.camera, lookup, in.boundary, i);
  ASSERT_TRUE(sides[1].used);
  const render::EdgeOnSideOptions options;
  const auto placed = render::PlaceEdgeOnSides(in.meshes, in.camera, lookup, in.boundary, sides,
                                               in.views, flat_diagonal, options);

  // Only the right side is edge-on, and the other photo sees it squarely.
  ASSERT_TRUE(placed[1].reference_cos);
  EXPECT_LT(*placed[1].reference_cos, options.max_cos);
  for (int i : {0, 2, 3}) {
    EXPECT_GT(placed[i].reference_cos.value_or(0), options.max_cos) << i;
    EXPECT_TRUE(placed[i].view.empty()) << i;
  }
  ASSERT_EQ(placed[1].view, "view_01.png");
  EXPECT_GT(placed[1].view_cos, 0.5);
  const render::SideFit from_view =
      render::FitSideLine(1, true, placed[1].flat, int(placed[1].flat.size()));
  ASSERT_TRUE(from_view.used);
  // The true right edge is x = kPageW in M'; the reference's grazing rays
  // put it far off on the wrong curl, the other photo's near it.
  const double mid = kPageH / 2;
  const double off_reference = std::abs(render::XAt(sides[1], mid) - kPageW);
  const double off_view = std::abs(render::XAt(from_view, mid) - kPageW);
  EXPECT_GT(off_reference, 0.01 * kPageW);
  EXPECT_LT(off_view, 0.4 * off_reference);

  // render places the side so, says so in its result, and without the
  // option keeps the reference's.
  const render::RenderResult r = render::Run({}, in);
  EXPECT_EQ(r.sides[1].placed_by, "view_01.png");
  EXPECT_LT(r.sides[1].reference_cos.value_or(1), options.max_cos);
  for (int i : {0, 2, 3}) EXPECT_TRUE(r.sides[i].placed_by.empty()) << i;
  render::RenderOptions off;
  off.edge_on_sides.max_cos = 0;
  const render::RenderResult before = render::Run(off, in);
  EXPECT_TRUE(before.sides[1].placed_by.empty());
  EXPECT_LT(std::abs(r.crop_x1 - kPageW), std::abs(before.crop_x1 - kPageW));

  // A photo beside the reference camera sees the curl as edge-on as it does:
  // it would save less than one depth error along the page, so the side
  // stays the reference's.
  render::ViewMask beside;
  beside.camera = LookingAt(Eigen::Vector3d(0.03, 0, 0), end);
  beside.camera.image = "view_02.png";
  beside.mask = RasterizeMesh(beside.camera, truth.mesh3d, truth.grid.Triangles()).face >= 0;
  const auto from_beside = render::PlaceEdgeOnSides(in.meshes, in.camera, lookup, in.boundary,
                                                    sides, {beside}, flat_diagonal, options);
  EXPECT_TRUE(from_beside[1].view.empty()) << from_beside[1].view_cos;
  render::EdgeOnSideOptions any_saving = options;  // the photo does see the side
  any_saving.min_tan_saving = -HUGE_VAL;
  EXPECT_EQ(render::PlaceEdgeOnSides(in.meshes, in.camera, lookup, in.boundary, sides, {beside},
                                     flat_diagonal, any_saving)[1]
                .view,
            "view_02.png");

  // No other photo: every side from the reference.
  in.views.clear();
  const auto alone = render::PlaceEdgeOnSides(in.meshes, in.camera, lookup, in.boundary, sides,
                                              in.views, flat_diagonal, options);
  for (const auto& p : alone) EXPECT_TRUE(p.view.empty());
}

// M that stops short of the curled end (a blank margin without points):
// render continues it straight past its border to where the page edge
// crosses it. The reference's grazing rays cross that continuation far from
// the true end; a photo that sees the end squarely crosses it near there.
TEST(RenderEdgeOnSides, AReachedSideIsPlacedWhereTheSquarestPhotoSeesItsEdge) {
  const SyntheticScene scene = CurledScene();
  ASSERT_TRUE(scene.real[1]);
  render::RenderInputs in = InputsOf(scene);
  in.meshes = CurledPage(kRadius, -0.08 * kPageW);  // M ends 8 % of the page short
  const render::ViewMask view = EndOnView(CurledPage(kRadius, 0));

  const render::RenderResult alone = render::Run({}, in);
  ASSERT_TRUE(alone.reached_sides[1].measured);
  EXPECT_TRUE(alone.reached_sides[1].placed_by.empty());
  const double off_alone = std::abs(alone.crop_x1 - kPageW);
  EXPECT_GT(off_alone, 0.02 * kPageW);

  // Here the photo's crossings lie 3.5 % of the page from the reference's:
  // more than the default allows (a straight continuation that no longer
  // follows the page), so the reference's stand.
  in.views = {view};
  const render::RenderResult guarded = render::Run({}, in);
  EXPECT_TRUE(guarded.reached_sides[1].placed_by.empty());
  EXPECT_NEAR(guarded.crop_x1, alone.crop_x1, 1 / alone.pixels_per_unit);

  // Allowed that far, the photo places the side near the true end.
  render::RenderOptions wide;
  wide.cut_sides.max_view_disagreement = 0.05;
  const render::RenderResult r = render::Run(wide, in);
  ASSERT_TRUE(r.reached_sides[1].measured);
  EXPECT_EQ(r.reached_sides[1].placed_by, "view_01.png");
  EXPECT_GT(r.reached_sides[1].placed_by_cos, 0.9);
  const double off = std::abs(r.crop_x1 - kPageW);
  std::printf(
      "[render] reached right side: crop %.4f from the reference, %.4f from view_01 (true edge "
      "%.4f)\n",
      alone.crop_x1, r.crop_x1, kPageW);
  EXPECT_LT(off, 0.25 * off_alone);

  // A photo whose page edge lies much farther out on the continuation (its
  // mask runs a tenth of the page past the edge) is not taken even then.
  in.views = {EndOnView(CurledPage(kRadius, 0.1 * kPageW))};
  const render::RenderResult kept = render::Run(wide, in);
  ASSERT_TRUE(kept.reached_sides[1].measured);
  EXPECT_TRUE(kept.reached_sides[1].placed_by.empty());
  EXPECT_NEAR(kept.crop_x1, alone.crop_x1, 1 / alone.pixels_per_unit);
}

}  // namespace
}  // namespace docunfold::testing
