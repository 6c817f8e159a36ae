// Ground truth of a data set (ground_truth/ beside images/) for tests: the
// library's (stages/evaluate/ground_truth.h) under the tests' namespace, and
// a loader that fails the current test instead of throwing.
#pragma once

#include <filesystem>
#include <optional>

#include "stages/evaluate/ground_truth.h"

namespace docunfold::testing {

namespace fs = std::filesystem;

using evaluate::CornerView;
using evaluate::GroundTruth;
using evaluate::LinesFromFlatScan;
using evaluate::ProjectedDiagonal;
using evaluate::TrueCorners;
using evaluate::TrueCornersInView;
using evaluate::TrueLine;
using evaluate::TrueLinesInView;
using evaluate::TrueOutlineInView;
using evaluate::TruePageMask;
using evaluate::TruePointSeen;
using evaluate::TruthLines;

// Loads ground_truth/ of a data set; fails the current test (and returns
// nullopt) when something is missing.
std::optional<GroundTruth> LoadGroundTruth(const fs::path& dataset);

}  // namespace docunfold::testing
