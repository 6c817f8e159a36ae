// The running program: its name and version, and the plain lines it logs
// on stderr. Apart from common/cli.h so that code which only logs does not
// compile CLI11's headers (about 10 s per translation unit).
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace docunfold {

// Version string of the whole project (from CMake).
const char* ProgramVersion();

// Name used as the prefix of every log line ("sfm: ...").
void SetProgramName(const std::string& name);
const std::string& ProgramName();

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
