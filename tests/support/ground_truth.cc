#include "tests/support/ground_truth.h"

#include <gtest/gtest.h>

namespace docunfold::testing {

std::optional<GroundTruth> LoadGroundTruth(const fs::path& dataset) {
  try {
    return evaluate::LoadGroundTruth(dataset);
  } catch (const std::exception& e) {
    ADD_FAILURE() << dataset << ": ground truth: " << e.what();
    return std::nullopt;
  }
}

}  // namespace docunfold::testing
