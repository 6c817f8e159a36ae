// optimize's lines.json as render reads it back for the deskew and the page's
// orientation (a function of its own so that it can be fuzzed alone).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <vector>

#include "common/axis_direction.h"

namespace docunfold::render {

namespace fs = std::filesystem;

struct LinesFile {
  // Each line's direction (its normal turned, the same modulo 90 degrees)
  // and its extent in M'.
  std::vector<DirectionVote> lines;
  // Of those, the text lines, each by its direction along the line.
  std::vector<DirectionVote> text_lines;
  std::optional<Eigen::Vector2d> text_down;  // text_down_flat, when given
};

// Throws InputError naming the file and the problem.
LinesFile ReadLinesFile(const fs::path& file);

}  // namespace docunfold::render
