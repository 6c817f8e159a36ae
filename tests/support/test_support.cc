#include "tests/support/test_support.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <random>

namespace docunfold::testing {

TempDir::TempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "docunfold";
  for (char& c : name)
    if (c == '/') c = '_';
  std::random_device rd;
  path_ = fs::temp_directory_path() / ("docunfold-test-" + name + "-" + std::to_string(rd()));
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  if (std::getenv("DOCUNFOLD_KEEP_TEST_DIRS")) return;
  std::error_code ec;
  fs::remove_all(path_, ec);
}

CommandResult RunCommand(const std::string& command_line) {
  CommandResult result;
  FILE* pipe = ::popen((command_line + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) result.output.append(buf.data(), n);
  int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

fs::path StageBinary(const std::string& name) { return fs::path(DOCUNFOLD_BIN_DIR) / name; }
fs::path SourceDir() { return fs::path(DOCUNFOLD_SOURCE_DIR); }
fs::path SampleDir(const std::string& name) { return SourceDir() / "samples" / name; }
fs::path RealisticDir() {
  if (const char* env = std::getenv("DOCUNFOLD_REALISTIC_DIR")) return env;
  fs::path p = SourceDir().parent_path() / "shared" / "realistic";
  std::error_code ec;
  return fs::is_directory(p, ec) ? p : fs::path();
}

std::string Quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}

}  // namespace docunfold::testing
