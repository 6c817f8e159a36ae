// Checks of a mesh pair that tests, init-mesh and optimize report.
#pragma once

#include "common/grid_mesh.h"

namespace docunfold::isometry {

// Relative edge-length difference |‖e‖ − ‖e'‖| / ‖e'‖ over every grid edge
// (rows and columns) of the pair: the isometry error in edge length.
struct EdgeLengthError {
  double mean = 0;
  double max = 0;
  int edges = 0;
};
EdgeLengthError IsometryEdgeError(const MeshPair& meshes);

// Bounding-box diagonal of M (the model size of the normalised frame).
double ModelSize(const MeshPair& meshes);

}  // namespace docunfold::isometry
