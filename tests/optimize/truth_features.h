// A perfect "external detector" for tests and experiments: the page's true
// straight lines (ground_truth/features.json) projected into the reference
// view and cut into short straight pieces, written as features.json.
#pragma once

#include <filesystem>
#include <string>

#include "common/json_io.h"
#include "tests/support/ground_truth.h"

namespace docunfold::testing {

// Text lines and rules (page edges are the boundary's job) seen by the true
// camera of `reference`, cut into pieces of at most `piece_px` pixels.
Json TruthFeatures(const GroundTruth& gt, const std::string& reference, double piece_px = 60);

}  // namespace docunfold::testing
