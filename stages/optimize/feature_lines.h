// Feature lines in M' (paper "Feature line generation"): the samples of the
// straight segments found in the reference image become markers on M (the
// viewing ray of each sample pixel meets M), and segments whose markers are
// close to one straight line in M' are merged into feature lines.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "common/axis_direction.h"
#include "common/camera.h"
#include "common/grid_mesh.h"
#include "common/isometry/isometry.h"

namespace docunfold::optimize {

// A straight piece of the page in the reference image: a detected segment
// (text or edge) or a real side of the page boundary.
struct Segment {
  std::string kind;                     // "text", "edge" or "boundary"
  int side = -1;                        // boundary: 0 top, 1 right, 2 bottom, 3 left
  std::vector<Eigen::Vector2d> pixels;  // samples along the polyline
};

// Samples of a polyline about every `step` pixels, both ends included.
std::vector<Eigen::Vector2d> SamplePolyline(const std::vector<Eigen::Vector2d>& polyline,
                                            double step);

// Every sample of every segment as a marker on M (`line` left at -1).
struct MarkerSet {
  std::vector<isometry::Marker> markers;
  std::vector<int> segment;             // per marker: index into the segments
  std::vector<Eigen::Vector2d> pixel;   // per marker: its reference pixel
  std::vector<int> markers_of_segment;  // per segment: markers found on M
};

struct CastOptions {
  // Samples whose ray misses M (page borders: half the pixel lies outside)
  // snap to the nearest covered pixel within this many pixels.
  double snap_px = 3;
  // The face-id image is rasterized at most this many pixels large.
  double max_raster_pixels = 2.5e6;
};

MarkerSet CastMarkers(const MeshPair& meshes, const PinholeCamera& reference,
                      const std::vector<Segment>& segments, const CastOptions& options = {});

struct GroupingOptions {
  // Tolerance box for the closest endpoints of two lines, as fractions of
  // the diagonal of M': length along the lines, and offset across them.
  double gap = 0.04;
  double offset = 0.003;
  double straightness = 0.1;       // h/w of the merged line's oriented box
  double axis_tolerance_deg = 12;  // keep lines this close to horizontal/vertical
  int min_markers = 3;             // fewer: the segment is not used
};

// Lines found in M': for every segment its line (or -1 when dropped), and
// per line its kind and, for a boundary side, which side.
struct Grouping {
  std::vector<int> line_of_segment;
  std::vector<std::string> line_kind;
  std::vector<int> line_side;
  std::vector<int> line_segments;  // number of segments per line
  int merges = 0;
};

// Merges segments (never boundary sides, never different kinds) whose
// closest endpoints lie in the tolerance box and whose union stays straight,
// repeated until nothing merges; keeps lines near the axes of the upright M'.
Grouping GroupSegments(const MeshPair& meshes, const MarkerSet& markers,
                       const std::vector<Segment>& segments, const GroupingOptions& options);

// The direction, modulo 90 degrees, that most of the detected segments'
// length follows in M' (text rows and rules run along the page's axes); the
// votes are the segments straight in M' (`lines` counts them). Boundary
// sides do not vote: init-mesh made M' upright by them already, and a side
// found wrongly (a fold taken for it) is what this checks.
AxisDirection DominantLineDirection(const MeshPair& meshes, const MarkerSet& markers,
                                    const std::vector<Segment>& segments);

// Which lines are held along the axes of M' (isometry::FeatureLine::
// axis_aligned): none (the paper), the detected text and rule lines, or
// those and the real page sides.
enum class AxisLines { kNone, kFeatures, kAll };

// Assigns each marker its segment's line; returns lines fitted (total least
// squares) to their markers' points in M'.
std::vector<isometry::FeatureLine> AssignLines(const MeshPair& meshes, const Grouping& grouping,
                                               MarkerSet* markers,
                                               AxisLines axis_lines = AxisLines::kNone);

// Markers inside a real page side (not in its last tenth at either end)
// farther than `tolerance` (fraction of the diagonal of M') and 4 robust
// sigma of the side's scatter from the side's fitted line lose their line:
// a fold's notch, not the page's edge, made that part of the outline.
// In the last tenths a marker loses it only when more than `end_factor`
// times that far off (0: never): there M is least certain and the line is
// what straightens the edge, but a sample whose ray grazes M's border can
// land anywhere along it. Returns how many were dropped.
int DropSideOutliers(const MeshPair& meshes, const Grouping& grouping, double tolerance,
                     MarkerSet* markers, double end_factor = 0);

}  // namespace docunfold::optimize
