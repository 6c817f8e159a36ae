// Command-line plumbing shared by every stage: parsing with CLI11 into an
// options struct, exception-to-exit-code mapping, and rate-limited logging.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "common/errors.h"
#include "common/option_table.h"

namespace docunfold {

// Version string of the whole project (from CMake).
const char* ProgramVersion();

// Name used as the prefix of every log line ("sfm: ...").
void SetProgramName(const std::string& name);
const std::string& ProgramName();

// Parses the command line into `options`' fields, runs `body` and maps what
// it throws to an exit code, printing exactly one line
// "<program>: <kind>: <message>" to stderr. CLI11 parse errors become exit 2
// (or 0 for --help / --version). `--help-markdown` prints the options' table
// for docs/stages/ instead.
int RunStage(const std::string& program, OptionTable& options, int argc, char** argv,
             const std::function<void()>& body);

// For programs that use Tesseract: its OpenMP parallelism (up to 10 threads
// per region) spins on few shared cores and makes OCR several times slower.
// libgomp reads OMP_THREAD_LIMIT only when it is loaded, so when the variable
// is unset this sets it to 1 and re-executes the program once (call first
// thing in main; returns normally when nothing needs doing or exec fails).
void LimitOpenMpThreads(char** argv);

// One plain line on stderr: "<program>: <message>".
void Log(const std::string& message);

// Progress of a long loop, logged at most about once a second, plus the last
// step when `Done` is called.
class Progress {
 public:
  Progress(std::string what, long total);
  void Update(long done);
  void Done();

 private:
  std::string what_;
  long total_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_;
};

// Seconds since `start` as a double; for summaries and log.json.
double SecondsSince(std::chrono::steady_clock::time_point start);

// `value` with `decimals` digits after the point ("%.*f"), for log lines.
std::string Fixed(double value, int decimals);

// Wall time of a stage's steps, for its summary line and the times in its
// JSON output.
class StepTimer {
 public:
  StepTimer();
  // Records the seconds since the previous Mark (or the start) under `step`
  // and returns them.
  double Mark(const std::string& step);
  // Seconds since the start.
  double Total() const;
  // (step, seconds) in the order marked.
  const std::vector<std::pair<std::string, double>>& steps() const { return steps_; }

 private:
  std::chrono::steady_clock::time_point start_, last_;
  std::vector<std::pair<std::string, double>> steps_;
};

}  // namespace docunfold
