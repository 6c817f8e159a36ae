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

TEST(DepthField, PlanarFitIsExactOnAPlane) {
  Points p;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j) {
      const double u = 20 * i + 3 * std::sin(i * 7 + j), v = 20 * j + 3 * std::cos(i + 5 * j);
      p.Add(u, v, PlaneDepth(u, v));
    }
  const DepthField field(p.pixels, p.depths, 3, 10, DepthModel::kPlanar, 16);
  for (const Eigen::Vector2d& px :
       {Eigen::Vector2d(55, 71), Eigen::Vector2d(130, 12), Eigen::Vector2d(201, 199)})
    EXPECT_NEAR(field.At(px), PlaneDepth(px.x(), px.y()), 1e-9);
}

}  // namespace
}  // namespace docunfold
