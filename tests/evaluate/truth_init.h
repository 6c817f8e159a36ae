// The true surface as init-mesh's pair of meshes, in the frame sfm chose: the
// perfect start for optimize. Optimize started there and rendered (the
// benchmark's `docunfold-from-truth` row) shows what optimize itself loses,
// apart from what init-mesh and the points lose before it.
#pragma once

#include <string>

#include "common/camera.h"
#include "common/grid_mesh.h"
#include "tests/support/ground_truth.h"

namespace docunfold::testing {

// M: the true surface at the grid's vertices, (s, t) = (col / (nx - 1),
// row / (ny - 1)) of flat.png, taken into `sfm_cameras`' frame by the
// similarity of the camera centres (evaluate's alignment, the inverse way).
// M': its exact flattening, the page's width and height in the same units,
// x right and y down as flat.png. Throws std::runtime_error when the cameras
// cannot be aligned or the grid is smaller than 2 x 2.
MeshPair TrueSurfaceOnGrid(const GroundTruth& gt, const CameraSet& sfm_cameras,
                           const QuadGrid& grid);

}  // namespace docunfold::testing
