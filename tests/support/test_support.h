// Helpers shared by tests: a private temporary directory per test, running
// the stage binaries, and locating samples.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/json_io.h"

namespace docunfold::testing {

namespace fs = std::filesystem;

// A fresh directory for the current test, removed at destruction unless
// DOCUNFOLD_KEEP_TEST_DIRS is set in the environment.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// The whole content of a file ("" when it cannot be read).
std::string ReadFileText(const fs::path& path);

// Runs a shell command line (arguments already quoted) and captures output.
CommandResult RunCommand(const std::string& command_line);

// Path of a built stage binary, e.g. StageBinary("sfm").
fs::path StageBinary(const std::string& name);
fs::path SourceDir();
// samples/<name>; also where synth-made fixtures live.
fs::path SampleDir(const std::string& name);
// ../shared/realistic relative to the source tree, or "" when absent.
fs::path RealisticDir();
// ../shared/realistic-hard (panels past upright, flaps, receipts), or "".
fs::path RealisticHardDir();

std::string Quote(const std::string& s);

// build/e2e/: the one run of the whole pipeline the e2e tests share
// (tests/pipeline/run_e2e.sh, CTest fixture e2e_run).
fs::path E2eDir();
// That run's benchmark rows of one set (results.json): method -> metrics.
std::map<std::string, Json> E2eRows(const std::string& set);
// rows[method][key], or NaN when absent or not a number.
double Metric(const std::map<std::string, Json>& rows, const std::string& method,
              const std::string& key);

// The message of the InputError `f` throws ("" when it throws none).
std::string ErrorOf(const std::function<void()>& f);

// Grey levels with the slowly varying shading divided out (BGR or grey in).
cv::Mat1f Detail(const cv::Mat& image);
// Normalised cross-correlation of two equally sized images over `mask`
// (all pixels when empty).
double Correlation(const cv::Mat1f& a, const cv::Mat1f& b, const cv::Mat1b& mask = {});

}  // namespace docunfold::testing
