#include "common/depth_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace docunfold {
namespace {

// Points of the plane 1/z = 0.5 + 0.001·u - 0.0005·v on a jittered grid.
struct Points {
  std::vector<Eigen::Vector2d> pixels;
  std::vector<double> depths;
  void Add(double u, double v, double depth) {
    pixels.emplace_back(u, v);
    depths.push_back(depth);
  }
};

double PlaneDepth(double u, double v) { return 1 / (0.5 + 0.001 * u - 0.0005 * v); }

TEST(DepthField, PlanarFitIsExactOnAPlaneWithOrWithoutTheGuard) {
  Points p;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j) {
      const double u = 20 * i + 3 * std::sin(i * 7 + j), v = 20 * j + 3 * std::cos(i + 5 * j);
      p.Add(u, v, PlaneDepth(u, v));
    }
  for (double guard : {0.0, 0.01}) {
    const DepthField field(p.pixels, p.depths, 3, 10, DepthModel::kPlanar, 16, guard);
    for (const Eigen::Vector2d& px :
         {Eigen::Vector2d(55, 71), Eigen::Vector2d(130, 12), Eigen::Vector2d(201, 199)})
      EXPECT_NEAR(field.At(px), PlaneDepth(px.x(), px.y()), 1e-9) << "guard " << guard;
  }
}

// A page at depth 1 with two short text lines near the query pixel, one of
// them lifted 4 % (a bump in the paper): the 16 nearest points are those two
// lines, their fit tilts the plane and, past the lifted line, reaches its
// depth. The 32 nearest take in the page around and disagree by more than
// 1 %: with the guard, the wider fit is taken.
TEST(DepthField, TheGuardTakesTheWiderFitWhereAFewClustersTiltTheNarrowOne) {
  Points p;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 2; ++j) {
      p.Add(-10 + 2 * i, -1 + 2 * j,
            1.0);                          // line at depth 1, left of the query
      p.Add(6 + 2 * i, -1 + 2 * j, 1.04);  // lifted line, right of the query
    }
  for (int k = 0; k < 24; ++k) {  // the page around, farther away
    const double a = 2 * M_PI * k / 24;
    p.Add(60 * std::cos(a), 60 * std::sin(a), 1.0);
  }
  const Eigen::Vector2d px(20, 0);
  const DepthField narrow(p.pixels, p.depths, 3, 2, DepthModel::kPlanar, 16, 0);
  const DepthField guarded(p.pixels, p.depths, 3, 2, DepthModel::kPlanar, 16, 0.01);
  EXPECT_GT(narrow.At(px), 1.03);
  EXPECT_LT(guarded.At(px), 1.02);
}

}  // namespace
}  // namespace docunfold
