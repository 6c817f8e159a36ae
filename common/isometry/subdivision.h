// Catmull-Clark subdivision of the pair (M, M') on the structured grid: an
// nx x ny vertex grid becomes (2nx-1) x (2ny-1). Interior rules of Catmull
// and Clark (all interior vertices have valence 4); on the open border the
// boundary rules that make the border curve a uniform cubic B-spline of the
// border polyline (edge points at midpoints, vertex points (1, 6, 1)/8), with
// the four grid corners kept fixed. The scheme is linear, so M' stays planar
// and both meshes are refined by the same map: the pair stays (approximately)
// isometric.
#pragma once

#include "common/grid_mesh.h"
#include "common/isometry/isometry.h"

namespace docunfold::isometry {

MeshPair SubdivideCatmullClark(const MeshPair& meshes);

// A surface point of the coarse pair expressed on the subdivided pair (the
// fine triangle under the same (u, v) of the coarse quad). The subdivided
// surface moves slightly, so markers found by ray casting should rather be
// recomputed; this keeps markers usable when that is not possible.
SurfacePoint SubdividedSurfacePoint(const QuadGrid& coarse, const SurfacePoint& p);

}  // namespace docunfold::isometry
