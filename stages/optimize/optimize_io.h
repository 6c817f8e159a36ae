// Files of the optimize stage: reading 10_sfm/, 20_boundary/, 30_features/
// and 40_init/, and writing 50_optimize/ (final and per-round meshes,
// lines.json, log.json, scene.glb).
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>

#include "common/json_io.h"
#include "stages/optimize/optimize.h"

namespace docunfold::optimize {

namespace fs = std::filesystem;

struct InputPaths {
  fs::path sfm;       // 10_sfm/
  fs::path boundary;  // 20_boundary/ or its boundary.json
  fs::path features;  // features.json
  fs::path init;      // 40_init/
  fs::path points;    // 3D points to fit; empty: sfm/points.ply
  fs::path PointsFile() const { return points.empty() ? sfm / "points.ply" : points; }
};

// Reads and checks every input (throws InputError naming file and problem);
// the other photos' page masks only when `view_masks` (the visual hull's).
OptimizeInputs ReadInputs(const InputPaths& paths, bool view_masks = true);

struct OutputOptions {
  bool scene = true;         // write scene.glb
  int texture_width = 2048;  // scene.glb's texture, pixels at most
};

// Declares the output flags (--scene/--no-scene) into `table`.
void DeclareOutputOptions(OptionTable& table, OutputOptions* options);

// Writes everything into `out` (each file atomically).
void WriteOutputs(const fs::path& out, const InputPaths& paths, const OptimizeInputs& in,
                  const OptimizeResult& result, const Json& options_record,
                  const OutputOptions& output_options);

// `text_down_flat`, when given, is the reader's down in M' (unit).
Json LinesJson(const std::vector<LineRecord>& lines, const Json& options_record,
               const std::optional<Eigen::Vector2d>& text_down_flat = std::nullopt);
Json LogJson(const OptimizeResult& result, const Json& options_record);

}  // namespace docunfold::optimize
