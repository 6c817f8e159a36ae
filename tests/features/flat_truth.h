// True straight lines of a page read off its flat scan (ground_truth/flat.png)
// for data sets whose ground truth has no features.json (the independently
// rendered sets): text baselines and printed rules, in flat.png pixels. The
// flat scan is undistorted and clean, so classical layout analysis is exact
// enough there; the test checks it against synth's own lines on every synth
// set that has both.
#pragma once

#include <vector>

#include "tests/support/ground_truth.h"

namespace docunfold::testing {

// Text baselines (kind "text": the bottom edge of the characters that sit on
// it) and rules (kind "rule": centre lines of long thin dark lines).
std::vector<TrueLine> LinesFromFlatScan(const GroundTruth& gt);

}  // namespace docunfold::testing
