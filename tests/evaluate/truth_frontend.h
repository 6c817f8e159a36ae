// A pipeline front end made from ground truth: what sfm and segment-boundary
// would write if they were perfect (10_sfm/ from tests/support/truth_frame,
// 20_boundary/ from the true page outline in the reference view). Lets the
// baselines, later stages and the benchmark run before (or without) the real
// front end, and isolates the later stages' error from the front end's.
#pragma once

#include <filesystem>
#include <string>

#include "tests/support/ground_truth.h"

namespace docunfold::testing {

// The view with the most page pixels among those that see the whole page
// (all four corners inside the image), or among all views when none does
// (cut-off data sets); throws std::runtime_error when no view sees the page.
std::string ChooseTrueReference(const GroundTruth& gt);

// Writes 20_boundary/{boundary.json, mask.png, overlay.png} of `reference`
// from the truth: corners and four sides are the projected page border; a
// side is `real` when all of it is inside the image.
void WriteBoundaryFromTruth(const GroundTruth& gt, const std::string& reference,
                            const fs::path& out_dir);

// Both of the above, into <work>/10_sfm and <work>/20_boundary; reference ""
// = ChooseTrueReference. Returns the reference used.
std::string WriteTruthFrontEnd(const GroundTruth& gt, const fs::path& work,
                               std::string reference = "");

}  // namespace docunfold::testing
