// OutlinePriorDepths on a flat page square to the camera: with outline
// points on three of its sides, the fourth (straight between its corners)
// completes the border whichever side it is, a grid row or a grid column.
#include "stages/init-mesh/outline_prior.h"

#include <gtest/gtest.h>

namespace docunfold::init_mesh {
namespace {

constexpr double kDepth = 2;

// The page spans pixels 300..500 across and 250..550 down; a 5 x 7 grid.
struct FlatPage {
  QuadGrid grid{5, 7};
  PinholeCamera camera;
  std::vector<Eigen::Vector2d> grid_pixels;
  std::array<std::vector<Eigen::Vector2d>, 4> sides;  // top right bottom left

  FlatPage() {
    camera.width = camera.height = 800;
    camera.K << 800, 0, 400, 0, 800, 400, 0, 0, 1;
    for (int r = 0; r < grid.ny; ++r)
      for (int c = 0; c < grid.nx; ++c) grid_pixels.emplace_back(300 + 50 * c, 250 + 50 * r);
    sides[0] = {{300, 250}, {500, 250}};
    sides[1] = {{500, 250}, {500, 550}};
    sides[2] = {{300, 550}, {500, 550}};
    sides[3] = {{300, 250}, {300, 550}};
  }

  // Outline points every 5 px along every side but `unseen`.
  OutlinePriorResult Run(int unseen) const {
    std::vector<Eigen::Vector2d> outline;
    for (int s = 0; s < 4; ++s) {
      if (s == unseen) continue;
      const Eigen::Vector2d a = sides[s][0], b = sides[s][1];
      const int n = int((b - a).norm() / 5);
      for (int k = 0; k <= n; ++k) outline.push_back(a + (b - a) * (double(k) / n));
    }
    const std::vector<double> outline_depths(outline.size(), kDepth);
    const std::vector<double> grid_depths(grid_pixels.size(), kDepth);
    return OutlinePriorDepths(grid, grid_pixels, grid_depths, sides, {true, true, true, true},
                              camera, outline, outline_depths, grid_pixels, grid_depths, {});
  }
};

TEST(OutlinePrior, ThreeMeasuredSidesCompleteTheBorderWhicheverSideIsUnseen) {
  const FlatPage page;
  for (int unseen = 0; unseen < 4; ++unseen) {
    const OutlinePriorResult r = page.Run(unseen);
    EXPECT_TRUE(r.used) << "unseen side " << unseen << ": " << r.note;
    EXPECT_EQ(r.measured_sides, 3) << unseen;
    EXPECT_LT(r.side_points[size_t(unseen)], 10) << unseen;  // the neighbours' end points
    ASSERT_EQ(r.depth.size(), page.grid_pixels.size()) << unseen;
    for (size_t v = 0; v < r.depth.size(); ++v)
      EXPECT_NEAR(r.depth[v], kDepth, 1e-9) << "unseen side " << unseen << ", vertex " << v;
  }
}

TEST(OutlinePrior, TwoMeasuredSidesAreNotEnough) {
  // Only the left and right sides measured: no prior.
  const FlatPage page;
  std::vector<Eigen::Vector2d> two;
  for (int k = 0; k <= 60; ++k) {
    two.emplace_back(300, 250 + 5 * k);
    two.emplace_back(500, 250 + 5 * k);
  }
  const std::vector<double> depths(two.size(), kDepth);
  const std::vector<double> grid_depths(page.grid_pixels.size(), kDepth);
  const OutlinePriorResult none = OutlinePriorDepths(
      page.grid, page.grid_pixels, grid_depths, page.sides, {true, true, true, true}, page.camera,
      two, depths, page.grid_pixels, grid_depths, {});
  EXPECT_FALSE(none.used);
  EXPECT_EQ(none.measured_sides, 2);
}

}  // namespace
}  // namespace docunfold::init_mesh
