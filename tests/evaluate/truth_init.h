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

// M: the true surface at the vertices of `like`'s grid, evenly spaced in
// (s, t) of flat.png over the page grown by `margin` (a fraction of its width
// and of its height) on every side, taken into `sfm_cameras`' frame by the
// similarity of the camera centres (evaluate's alignment, the inverse way).
// Past the page the surface runs on in the tangent plane at its border, as
// init-mesh's M runs on past the page so that the rays through the outline
// meet it. M': its exact flattening in the same units, turned the way
// `like`'s M' is (init-mesh turns its M' upright by the text; flat.png's axes
// when `like` has only a grid), the grid's rows along its x. Throws
// std::runtime_error when the cameras cannot be aligned, `like`'s M' is no
// quarter turn of the page, or the grid is smaller than 2 x 2.
MeshPair TrueSurfaceOnGrid(const GroundTruth& gt, const CameraSet& sfm_cameras,
                           const MeshPair& like, double margin = 0.01);

}  // namespace docunfold::testing
