// Every JSON file shipped with or read by docunfold validates against its
// schema in schemas/, and the validator reports problems as file:/pointer.
#include <gtest/gtest.h>

#include <fstream>

#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

std::string Validator() { return Quote((SourceDir() / "scripts" / "validate-json").string()); }

std::vector<fs::path> JsonFilesUnder(const fs::path& root) {
  std::vector<fs::path> files;
  std::error_code ec;
  if (!fs::is_directory(root, ec)) return files;
  for (const auto& e : fs::recursive_directory_iterator(root))
    if (e.is_regular_file() && e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

void ExpectAllValid(const std::vector<fs::path>& files) {
  for (const fs::path& f : files) {
    CommandResult r = RunCommand(Validator() + " " + Quote(f.string()));
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
}

TEST(Schemas, AreValidJsonSchemas) {
  CommandResult r = RunCommand(Validator() + " --check-schemas");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(Schemas, EverySampleFileValidates) {
  auto files = JsonFilesUnder(SourceDir() / "samples");
  if (files.empty()) GTEST_SKIP() << "no samples";
  ExpectAllValid(files);
}

TEST(Schemas, IndependentRealisticSetsValidate) {
  fs::path dir = RealisticDir();
  if (dir.empty()) GTEST_SKIP() << "../shared/realistic is absent";
  auto files = JsonFilesUnder(dir);
  ASSERT_FALSE(files.empty());
  ExpectAllValid(files);
}

TEST(Schemas, ProblemsNameTheFileAndPointer) {
  TempDir dir;
  std::ofstream(dir / "bad.json")
      << R"({"format": "docunfold.gt-cameras", "version": 1, "views": [{"image": "a.jpg",
            "width": 10, "height": 10, "K": [[1,0,0],[0,1,0],[0,0,1]],
            "R": [[1,0,0],[0,1,0],[0,0,1]], "t": [0, 0]}]})";
  CommandResult r = RunCommand(Validator() + " " + Quote((dir / "bad.json").string()));
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.output.find("bad.json:/views/0/t: "), std::string::npos) << r.output;

  std::ofstream(dir / "empty.json");
  r = RunCommand(Validator() + " " + Quote((dir / "empty.json").string()));
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.output.find("empty.json: empty file"), std::string::npos) << r.output;

  std::ofstream(dir / "unknown.json") << R"({"format": "other.thing", "version": 1})";
  r = RunCommand(Validator() + " " + Quote((dir / "unknown.json").string()));
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.output.find("unknown.json:/format: unknown format"), std::string::npos);
}

}  // namespace
}  // namespace docunfold::testing
