// Inputs for render made from ground truth (true meshes, true page outline)
// or from a small analytic scene whose exact rendering is known.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"
#include "stages/render/render.h"
#include "tests/support/ground_truth.h"

namespace docunfold::testing {

// Every data set with ground truth (samples/* and the realistic sets).
std::vector<fs::path> RenderDataSets();

// What render would read for a data set if sfm, segment-boundary and the
// mesh stages were exact: the first true view as reference (camera in its
// own frame scaled to median depth 1, the photo), the true surface as M and
// M', and the true page outline as the boundary (a side is real when at
// least half of it is inside the image; then only that part is kept).
struct TruthInputs {
  PinholeCamera camera;
  cv::Mat3b photo;
  MeshPair meshes;
  std::array<std::vector<Eigen::Vector2d>, 4> sides;
  std::array<bool, 4> real{};
};
TruthInputs MakeTruthInputs(const GroundTruth& gt);

// A boundary.json with the given four sides (top TL->TR, right TR->BR,
// bottom BL->BR, left TL->BL) and `real` flags.
void WriteBoundaryJson(const fs::path& file, int width, int height,
                       const std::array<std::vector<Eigen::Vector2d>, 4>& sides,
                       const std::array<bool, 4>& real);

// An analytic scene: a page of `page_w` x `page_h` units (texture
// `texture`, one texture pixel = page_w / texture.cols units) bent about a
// vertical axis into a cylinder of radius `radius` over its right half
// (an exact isometry), seen by `camera`. The photo is rendered with 3x3
// supersampling; the sides are the projected page border.
struct SyntheticScene {
  cv::Mat3b texture;
  double page_w = 0, page_h = 0;
  PinholeCamera camera;
  MeshPair meshes;
  cv::Mat3b photo;
  std::array<std::vector<Eigen::Vector2d>, 4> sides;
  std::array<bool, 4> real{};
};

struct SceneOptions {
  int image_width = 640, image_height = 480;
  double focal = 700;
  Eigen::Vector3d page_origin{-0.22, -0.3, 1.0};  // top-left corner, camera frame
  double radius = 0.25;                           // of the bend (0 = flat)
  double tilt_deg = 20;                           // page turned about the camera's x axis
  int texture_width = 480, texture_height = 640;
  double page_w = 0.42, page_h = 0.56;
};

// A texture with text, rules and fine stripes (aliasing shows on it).
cv::Mat3b MakeTexture(int width, int height);

SyntheticScene MakeScene(const SceneOptions& options);

// Writes the scene as 10_sfm/, 20_boundary/ and 40_init/ under `work`.
void WriteScene(const SyntheticScene& scene, const fs::path& work);

// The same as render's in-memory inputs.
render::RenderInputs InputsOf(const SyntheticScene& scene);
render::RenderInputs InputsOf(const TruthInputs& truth);

// Where the content of `ref` is found in `moved`: tiles of `tile` pixels of
// `ref` with enough texture are searched for in `moved` within +-`radius`
// pixels (normalised cross-correlation, sub-pixel peak); only tiles whose
// search window lies inside `mask` take part; tiles whose best match is not
// clearly better than any other more than 3 pixels away (a lone rule) are
// not counted.
struct TileOffsets {
  int tiles = 0;      // textured tiles with an unambiguous match
  int matched = 0;    // found with a correlation above 0.5
  double median = 0;  // offset length of the matched tiles, pixels
  double p90 = 0;
  double max = 0;
};
TileOffsets FindTileOffsets(const cv::Mat1f& ref, const cv::Mat1f& moved, const cv::Mat1b& mask,
                            int tile, int radius);

}  // namespace docunfold::testing
