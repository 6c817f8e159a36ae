// CastMarkers on a flat sheet seen square-on: with --border-snap, samples of
// a real page side that lie off M's image go on M's border (so the ray term
// can pull the border to the outline); other segments' samples off M, and
// every sample without it, are dropped.
#include <gtest/gtest.h>

#include "stages/optimize/feature_lines.h"

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
    EXPECT_GT(set.markers[i].ray_direction.dot(
                  scene.camera.RayDirection(set.pixel[i])), 1 - 1e-12);
  }
  // Beyond the radius, or by default (off): none.
  EXPECT_EQ(CastMarkers(scene.meshes, scene.camera, {LeftOf("boundary", 30)}, Snapping())
                .markers_of_segment[0],
            0);
  EXPECT_EQ(CastMarkers(scene.meshes, scene.camera, {LeftOf("boundary", 12)})
                .markers_of_segment[0],
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

}  // namespace
}  // namespace docunfold::optimize
