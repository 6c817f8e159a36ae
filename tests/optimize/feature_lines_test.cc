// CastMarkers on a flat sheet seen square-on: with --border-snap, samples of
// a real page side that lie off M's image go on M's border (so the ray term
// can pull the border to the outline); other segments' samples off M, and
// every sample without it, are dropped.
#include "stages/optimize/feature_lines.h"

#include <gtest/gtest.h>

namespace docunfold::optimize {
namespace {

// A 1 x 1.5 sheet at z = 4 in front of a 800 x 800 camera (f = 800): the
// sheet spans pixels 300..500 across and 250..550 down.
struct Scene {
  MeshPair meshes;
  PinholeCamera camera;

  Scene() {
    camera.width = camera.height = 800;
    camera.K << 800, 0, 400, 0, 800, 400, 0, 0, 1;
    meshes.grid = {5, 7};
    for (int r = 0; r < 7; ++r)
      for (int c = 0; c < 5; ++c) {
        const Eigen::Vector2d flat(-0.5 + 0.25 * c, -0.75 + 0.25 * r);
        meshes.mesh2d.push_back(flat);
        meshes.mesh3d.emplace_back(flat.x(), flat.y(), 4.0);
      }
  }
};

CastOptions Snapping() {
  CastOptions o;
  o.border_snap = 0.02;  // of the diagonal: 22.6 px
  return o;
}

// A vertical segment `offset` pixels left of the sheet's left border.
Segment LeftOf(const std::string& kind, double offset) {
  Segment s;
  s.kind = kind;
  s.side = kind == "boundary" ? 3 : -1;
  s.pixels = SamplePolyline({{300 - offset, 280}, {300 - offset, 520}}, 4);
  return s;
}

TEST(CastMarkers, PageSideSamplesOffTheMeshGoOnItsBorder) {
  const Scene scene;
  const std::vector<Segment> segments = {LeftOf("boundary", 12), LeftOf("text", 12)};
  const MarkerSet set = CastMarkers(scene.meshes, scene.camera, segments, Snapping());
  ASSERT_EQ(set.markers_of_segment.size(), 2u);
  EXPECT_EQ(set.markers_of_segment[0], int(segments[0].pixels.size()));
  EXPECT_EQ(set.markers_of_segment[1], 0);  // a text segment off the page
  for (size_t i = 0; i < set.markers.size(); ++i) {
    // On the left border (flat x = -0.5), level with its pixel, and its ray
    // is the pixel's own.
    const Eigen::Vector2d flat = PointOnMesh2d(scene.meshes, set.markers[i].where);
    EXPECT_NEAR(flat.x(), -0.5, 1e-9) << i;
    EXPECT_NEAR(flat.y(), (set.pixel[i].y() - 400) / 800 * 4, 1e-9) << i;
    EXPECT_GT(set.markers[i].ray_direction.dot(scene.camera.RayDirection(set.pixel[i])), 1 - 1e-12);
  }
  // Beyond the radius, or by default (off): none.
  EXPECT_EQ(CastMarkers(scene.meshes, scene.camera, {LeftOf("boundary", 30)}, Snapping())
                .markers_of_segment[0],
            0);
  EXPECT_EQ(CastMarkers(scene.meshes, scene.camera, {LeftOf("boundary", 12)}).markers_of_segment[0],
            0);
}

TEST(CastMarkers, OutlineSamplesNearACornerKeepToTheirOwnSide) {
  // The left side's samples above the sheet's top-left corner still go on
  // the left border (its nearest edge by direction), not on the top one.
  const Scene scene;
  Segment left;
  left.kind = "boundary";
  left.side = 3;
  left.pixels = SamplePolyline({{292, 244}, {292, 300}}, 4);
  const MarkerSet set = CastMarkers(scene.meshes, scene.camera, {left}, Snapping());
  ASSERT_EQ(set.markers_of_segment[0], int(left.pixels.size()));
  for (const auto& m : set.markers)
    EXPECT_NEAR(PointOnMesh2d(scene.meshes, m.where).x(), -0.5, 1e-9);
}

// A real left side 5 px inside the sheet's border, with `bumps`: runs of
// samples pushed `bump_px` into the page (a fold's notch in the outline).
MarkerSet SideWithBumps(const Scene& scene, const std::vector<std::pair<int, int>>& bumps,
                        Grouping* grouping, int bump_px = 12) {
  Segment side;
  side.kind = "boundary";
  side.side = 3;
  for (int y = 260; y <= 540; y += 4) {
    bool bumped = false;
    for (const auto& [from, to] : bumps) bumped = bumped || (y >= from && y <= to);
    side.pixels.emplace_back(bumped ? 305 + bump_px : 305, y);
  }
  MarkerSet set = CastMarkers(scene.meshes, scene.camera, {side});
  grouping->line_of_segment = {0};
  grouping->line_kind = {"boundary"};
  grouping->line_side = {3};
  grouping->line_segments = {1};
  AssignLines(scene.meshes, *grouping, &set, AxisLines::kAll);
  return set;
}

TEST(DropSideOutliers, ANotchInsideTheSideLosesItsLineItsEndsDoNot) {
  const Scene scene;
  Grouping grouping;
  // Middle: 5 samples (392..408) off the side; near the start (within a
  // tenth of the side's length) 3 samples (264..272) that stay.
  MarkerSet set = SideWithBumps(scene, {{392, 408}, {264, 272}}, &grouping);
  ASSERT_EQ(set.markers.size(), 71u);
  EXPECT_EQ(DropSideOutliers(scene.meshes, grouping, 0.005, &set), 5);
  for (size_t i = 0; i < set.markers.size(); ++i) {
    const double y = set.pixel[i].y();
    EXPECT_EQ(set.markers[i].line, y >= 392 && y <= 408 ? -1 : 0) << "y " << y;
  }
  // A straight side keeps every marker; so does a notch within tolerance,
  // and a long run off the line (a third of the side: no notch).
  MarkerSet straight = SideWithBumps(scene, {}, &grouping);
  EXPECT_EQ(DropSideOutliers(scene.meshes, grouping, 0.005, &straight), 0);
  MarkerSet notched = SideWithBumps(scene, {{392, 408}}, &grouping);
  EXPECT_EQ(DropSideOutliers(scene.meshes, grouping, 0.05, &notched), 0);
  MarkerSet long_run = SideWithBumps(scene, {{360, 452}}, &grouping);
  EXPECT_EQ(DropSideOutliers(scene.meshes, grouping, 0.005, &long_run), 0);
}

TEST(DropSideOutliers, AtTheEndsOnlyFarOutliersLoseTheirLine) {
  const Scene scene;
  Grouping grouping;
  // The end's 12 px bump is within 4 times the limit and stays, as with 0.
  MarkerSet near = SideWithBumps(scene, {{392, 408}, {264, 272}}, &grouping);
  EXPECT_EQ(DropSideOutliers(scene.meshes, grouping, 0.005, &near, 4), 5);
  // The first sample 60 px into the page (its ray grazed M's border and
  // met M elsewhere) goes with end_factor 4, and stays with 0 (old rule).
  MarkerSet far = SideWithBumps(scene, {{260, 260}}, &grouping, 60);
  MarkerSet far_kept = far;
  EXPECT_EQ(DropSideOutliers(scene.meshes, grouping, 0.005, &far, 4), 1);
  for (size_t i = 0; i < far.markers.size(); ++i)
    EXPECT_EQ(far.markers[i].line, i == 0 ? -1 : 0) << "y " << far.pixel[i].y();
  EXPECT_EQ(DropSideOutliers(scene.meshes, grouping, 0.005, &far_kept, 0), 0);
}

TEST(CornerMarkers, HoldTheGridCornersToTheRaysOfRealCornersNearThem) {
  const Scene scene;
  Boundary boundary;
  boundary.corners = {Eigen::Vector2d(300, 250), Eigen::Vector2d(500, 250),
                      Eigen::Vector2d(530, 580), Eigen::Vector2d(304, 547)};
  for (BoundarySide& side : boundary.sides) side.real = true;
  // BR is 42 px from the grid's corner, the others within 5 px.
  EXPECT_EQ(HeldCorners(scene.meshes, boundary, scene.camera, 20),
            (std::array<bool, 4>{true, true, false, true}));
  EXPECT_EQ(HeldCorners(scene.meshes, boundary, scene.camera, 50),
            (std::array<bool, 4>{true, true, true, true}));
  // A corner on a cut side is no page corner.
  Boundary cut = boundary;
  cut.sides[2].real = false;
  EXPECT_EQ(HeldCorners(scene.meshes, cut, scene.camera, 50),
            (std::array<bool, 4>{true, true, false, false}));

  const std::array<bool, 4> held = {true, true, true, true};
  const std::vector<isometry::Marker> markers =
      CornerMarkers(scene.meshes, boundary, scene.camera, held);
  ASSERT_EQ(markers.size(), 4u);
  const int corner_vertex[4] = {0, 4, 34, 30};  // TL TR BR BL of the 5 x 7 grid
  for (int k = 0; k < 4; ++k) {
    const isometry::Marker& m = markers[k];
    EXPECT_EQ(m.line, -1);
    EXPECT_TRUE(m.across.isZero());
    EXPECT_LT((PointOnMesh3d(scene.meshes, m.where) - scene.meshes.mesh3d[corner_vertex[k]]).norm(),
              1e-12)
        << k;
    EXPECT_GT(m.ray_direction.dot(scene.camera.RayDirection(boundary.corners[k])), 1 - 1e-12);
  }
  EXPECT_EQ(CornerMarkers(scene.meshes, boundary, scene.camera, {false, true, false, false}).size(),
            1u);
}

}  // namespace
}  // namespace docunfold::optimize
