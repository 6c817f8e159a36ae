// The subprocess runner (COLMAP, poppler's tools): output lines, exit code,
// log, time limit, a program that is not there.
#include "common/subprocess.h"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

TEST(SubprocessTest, CapturesLinesExitCodeAndLog) {
  TempDir tmp;
  std::vector<std::string> lines;
  SubprocessOptions o;
  o.log_file = tmp / "run.log";
  o.on_line = [&](const std::string& l) { lines.push_back(l); };
  const auto r = RunSubprocess({"sh", "-c", "echo one; echo two >&2; printf 'three'; exit 3"}, o);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_FALSE(r.timed_out);
  EXPECT_FALSE(r.not_found);
  EXPECT_EQ(lines, (std::vector<std::string>{"one", "two", "three"}));
  std::ifstream f(o.log_file);
  const std::string log((std::istreambuf_iterator<char>(f)), {});
  EXPECT_NE(log.find("two"), std::string::npos);
  EXPECT_NE(log.find("# exit 3"), std::string::npos);
}

TEST(SubprocessTest, TimeoutKillsTheWholeProcessGroup) {
  TempDir tmp;
  SubprocessOptions o;
  o.log_file = tmp / "run.log";
  o.timeout_seconds = 0.5;
  const auto start = std::chrono::steady_clock::now();
  // The child starts a grandchild; both must go.
  const auto r = RunSubprocess({"sh", "-c", "sleep 30 & sleep 30; wait"}, o);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_TRUE(r.timed_out);
  EXPECT_LT(seconds, 10);
}

TEST(SubprocessTest, MissingProgram) {
  TempDir tmp;
  SubprocessOptions o;
  o.log_file = tmp / "run.log";
  EXPECT_TRUE(RunSubprocess({"/nonexistent/colmap"}, o).not_found);
  EXPECT_TRUE(RunSubprocess({"no-such-program-docunfold"}, o).not_found);
  EXPECT_TRUE(FindExecutable("no-such-program-docunfold").empty());
  EXPECT_FALSE(FindExecutable("sh").empty());
}

TEST(SubprocessTest, WithoutALogFileOnlyTheLinesAreKept) {
  std::string out;
  SubprocessOptions o;
  o.on_line = [&](const std::string& l) { out += l + "\n"; };
  const auto r = RunSubprocess({"sh", "-c", "echo one; echo two >&2"}, o);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(out, "one\ntwo\n");
}

}  // namespace
}  // namespace docunfold::testing
