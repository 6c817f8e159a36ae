// synth: photographed creased pages with full ground truth: a data set of
// photos (images/) and the truth they were made from (ground_truth/: the flat
// page, its text, size, surface, cameras and straight lines).
#pragma once

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/json_io.h"
#include "common/option_table_fwd.h"
#include "stages/synth/folds.h"
#include "stages/synth/page.h"
#include "stages/synth/scene.h"

namespace docunfold::synth {

namespace fs = std::filesystem;

struct SynthOptions {
  fs::path out;        // data-set folder to create
  bool force = false;  // replace an existing folder
  uint32_t seed = 1;   // everything random derives from it
  PageKind kind = PageKind::kText;
  cv::Size2d page_size_m{0, 0};   // 0: the kind's default (DefaultPageSize)
  int roll_mm = 0;                // receipt: the till roll's width (58 or 80), 0 the older layout
  FoldOptions folds;              // creases, curl, widths and angles
  ShapeOptions shapes;            // flap, steep fold, end curl
  CameraOptions cameras;          // views, image size, field of view, elevation, cut-off
  RenderOptions render;           // background, noise, JPEG quality
  double flat_dpi = 150;          // resolution of ground_truth/flat.png
  double texture_dpi = 300;       // resolution the page is printed at for rendering
  double mesh_spacing_m = 0.002;  // vertex spacing of ground_truth/mesh.ply
  std::string command_line;       // recorded in COMMAND beside the data
};

struct SynthResult {
  int views = 0;
  int mesh_vertices = 0;
  int folds = 0;
  double seconds = 0;
};

// Declares every option of SynthOptions but out (a path) and command_line;
// the lengths given in millimetres are kept in metres.
void DeclareOptions(OptionTable& table, SynthOptions* options);

// Makes the data set in options.out (written to a temporary folder and
// renamed into place); ground_truth/synth.json records `options_record`.
// Throws UsageError, OutputError or std::runtime_error.
SynthResult Run(const SynthOptions& options, const Json& options_record);

}  // namespace docunfold::synth
