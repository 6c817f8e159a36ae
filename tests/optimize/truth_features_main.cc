// truth-features DATA REFERENCE OUT.json: the true lines of DATA's page seen
// by view REFERENCE, as a features.json (a perfect detector, for tests and
// experiments with FEATURES=).
#include <iostream>

#include "common/json_io.h"
#include "tests/optimize/truth_features.h"

int main(int argc, char** argv) {
  using namespace docunfold;
  if (argc != 4) {
    std::cerr << "usage: truth-features DATA REFERENCE OUT.json\n";
    return 2;
  }
  try {
    auto gt = testing::LoadGroundTruth(argv[1]);
    if (!gt) return 3;
    WriteJsonAtomic(argv[3], testing::TruthFeatures(*gt, argv[2]));
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "truth-features: " << e.what() << "\n";
    return 3;
  }
}
