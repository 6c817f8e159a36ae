// CastMarkers on a flat sheet seen square-on: which samples become markers
// and where; DropSideOutliers on a real page side with notches.
#include "stages/optimize/feature_lines.h"

#include <gtest/gtest.h>

#include "tests/optimize/flat_sheet.h"

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
    meshes = FlatSheetAtDepthFour();
  }
};

// A vertical segment `offset` pixels left of the sheet's left border.
Segment LeftOf(const std::string& kind, double offset) {
  Segment s;
  s.kind = kind;
  s.side = kind == "boundary" ? 3 : -1;
  s.pixels = SamplePolyline({{300 - offset, 280}, {300 - offset, 520}}, 4);
  return s;
}

TEST(CastMarkers, SamplesOnTheMeshBecomeMarkersOthersAreDropped) {
  const Scene scene;
  // 2 px off M's image: snapped to a border triangle (within
  // CastOptions::snap_px), whose plane extended meets the pixel's own ray.
  const std::vector<Segment> near = {LeftOf("boundary", 2), LeftOf("text", 2)};
  const MarkerSet set = CastMarkers(scene.meshes, scene.camera, near);
  ASSERT_EQ(set.markers_of_segment.size(), 2u);
  EXPECT_EQ(set.markers_of_segment[0], int(near[0].pixels.size()));
  EXPECT_EQ(set.markers_of_segment[1], int(near[1].pixels.size()));
  for (size_t i = 0; i < set.markers.size(); ++i) {
    const Eigen::Vector2d flat = PointOnMesh2d(scene.meshes, set.markers[i].where);
    EXPECT_NEAR(flat.x(), (set.pixel[i].x() - 400) / 800 * 4, 1e-9) << i;
    EXPECT_NEAR(flat.y(), (set.pixel[i].y() - 400) / 800 * 4, 1e-9) << i;
    EXPECT_GT(set.markers[i].ray_direction.dot(scene.camera.RayDirection(set.pixel[i])), 1 - 1e-12);
  }
  // 12 px off: dropped, a page side's samples as any other's.
  const MarkerSet off =
      CastMarkers(scene.meshes, scene.camera, {LeftOf("boundary", 12), LeftOf("text", 12)});
  EXPECT_EQ(off.markers_of_segment[0], 0);
  EXPECT_EQ(off.markers_of_segment[1], 0);
  EXPECT_TRUE(off.markers.empty());
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

}  // namespace
}  // namespace docunfold::optimize
