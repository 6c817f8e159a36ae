// Running an external program (COLMAP, poppler's pdftotext) with its output
// going to a log file instead of our stderr, a time limit, and a callback per
// output line so the caller can turn the program's own messages into ours.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace docunfold {

namespace fs = std::filesystem;

struct SubprocessOptions {
  // Every line the program prints (stdout and stderr, merged) is appended
  // here (empty: no log). Must be writable.
  fs::path log_file;
  // The program is killed (with its process group) after this many seconds;
  // <= 0: no limit.
  double timeout_seconds = 0;
  // Called for each complete output line (without the newline).
  std::function<void(const std::string&)> on_line;
};

struct SubprocessResult {
  int exit_code = -1;      // the program's exit status; -1 if killed/crashed
  int signal = 0;          // the signal that ended it, if any
  bool timed_out = false;  // killed because of timeout_seconds
  bool not_found = false;  // the executable could not be started
  double seconds = 0;      // wall time
};

// Runs `argv[0]` (looked up in PATH when it has no '/') with the given
// arguments. Never throws for a failing program; throws OutputError when the
// log file cannot be written.
SubprocessResult RunSubprocess(const std::vector<std::string>& argv,
                               const SubprocessOptions& options);

// Full path of `program` found in PATH (or `program` itself when it contains
// a '/' and is executable); empty when there is none.
fs::path FindExecutable(const std::string& program);

}  // namespace docunfold
