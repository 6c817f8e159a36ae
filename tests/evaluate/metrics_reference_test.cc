// evaluate reproduces MS-SSIM and CER computed independently by the
// literature's definitions (DocUNet's MS-SSIM, CER as edit distance over
// reference length; ../shared/metrics-reference/*/expected.json):
// MS-SSIM within 0.003, CER within 0.01. Skips when the folder is absent.
#include <gtest/gtest.h>

#include <cstdlib>

#include "common/json_io.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

fs::path SharedDir() {
  if (const char* env = std::getenv("DOCUNFOLD_SHARED_DIR")) return env;
  return SourceDir().parent_path() / "shared";
}

std::vector<std::string> ReferencePairs() {
  std::vector<std::string> names;
  std::error_code ec;
  const fs::path dir = SharedDir() / "metrics-reference";
  if (!fs::is_directory(dir, ec)) return names;
  for (const auto& e : fs::directory_iterator(dir))
    if (fs::is_regular_file(e.path() / "expected.json")) names.push_back(e.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

class MetricsReference : public ::testing::TestWithParam<std::string> {};

TEST_P(MetricsReference, ReproducesMsSsimAndCer) {
  const fs::path pair = SharedDir() / "metrics-reference" / GetParam();
  const Json expected = ReadJsonFile(pair / "expected.json");
  const fs::path flat = SharedDir() / expected["ground_truth_flat"].get<std::string>();
  ASSERT_EQ(flat.filename(), "flat.png");
  ASSERT_EQ(flat.parent_path().filename(), "ground_truth");
  const fs::path data = flat.parent_path().parent_path();
  TempDir dir;
  const fs::path out = dir / "metrics.json";
  CommandResult r = RunCommand(
      Quote(StageBinary("evaluate").string()) + " --data " + Quote(data.string()) + " --result " +
      Quote((pair / expected["result"].get<std::string>()).string()) + " --out " +
      Quote(out.string()) + " --no-flow --no-geometry --method " + GetParam());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json m = ReadJsonFile(out)["metrics"];
  const double ms_ssim = m["ms_ssim"].get<double>(), cer = m["cer"].get<double>();
  std::cout << GetParam() << ": MS-SSIM expected " << expected["ms_ssim"] << " got " << ms_ssim
            << "; CER expected " << expected["cer"] << " got " << cer << "\n";
  EXPECT_NEAR(ms_ssim, expected["ms_ssim"].get<double>(), 0.003);
  EXPECT_NEAR(cer, expected["cer"].get<double>(), 0.01);
}

INSTANTIATE_TEST_SUITE_P(Pairs, MetricsReference, ::testing::ValuesIn(ReferencePairs()),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(MetricsReference);

TEST(MetricsReferenceData, PresentOrSkipped) {
  if (ReferencePairs().empty())
    GTEST_SKIP() << SharedDir() / "metrics-reference"
                 << " is absent";
  EXPECT_GE(ReferencePairs().size(), 2u);
}

}  // namespace
}  // namespace docunfold::testing
