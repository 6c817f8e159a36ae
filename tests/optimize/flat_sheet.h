// The 1 x 1.5 sheet the optimize unit tests look at: a 5 x 7 grid, 0.25
// apart, M in the plane z = 4 and M' its exact flattening.
#pragma once

#include "common/grid_mesh.h"

namespace docunfold::optimize {

inline MeshPair FlatSheetAtDepthFour() {
  MeshPair meshes;
  meshes.grid = {5, 7};
  for (int r = 0; r < 7; ++r)
    for (int c = 0; c < 5; ++c) {
      const Eigen::Vector2d flat(-0.5 + 0.25 * c, -0.75 + 0.25 * r);
      meshes.mesh2d.push_back(flat);
      meshes.mesh3d.emplace_back(flat.x(), flat.y(), 4.0);
    }
  return meshes;
}

}  // namespace docunfold::optimize
