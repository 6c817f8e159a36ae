#include "common/program.h"

#include <cstdio>
#include <iostream>

namespace docunfold {
namespace {
std::string& MutableProgramName() {
  static std::string name = "docunfold";
  return name;
}
}  // namespace

const char* ProgramVersion() { return DOCUNFOLD_VERSION; }

void SetProgramName(const std::string& name) { MutableProgramName() = name; }
const std::string& ProgramName() { return MutableProgramName(); }

void Log(const std::string& message) { std::cerr << ProgramName() << ": " << message << std::endl; }

Progress::Progress(std::string what, long total)
    : what_(std::move(what)),
      total_(total),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

void Progress::Update(long done) {
  auto now = std::chrono::steady_clock::now();
  if (now - last_ < std::chrono::seconds(1)) return;
  last_ = now;
  Log(what_ + " " + std::to_string(done) + "/" + std::to_string(total_));
}

void Progress::Done() {
  char buf[64];
  std::snprintf(buf, sizeof buf, " in %.1f s", SecondsSince(start_));
  Log(what_ + " " + std::to_string(total_) + "/" + std::to_string(total_) + buf);
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string Fixed(double value, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

StepTimer::StepTimer() : start_(std::chrono::steady_clock::now()), last_(start_) {}

double StepTimer::Mark(const std::string& step) {
  const auto now = std::chrono::steady_clock::now();
  const double seconds = std::chrono::duration<double>(now - last_).count();
  steps_.emplace_back(step, seconds);
  last_ = now;
  return seconds;
}

double StepTimer::Total() const { return SecondsSince(start_); }

}  // namespace docunfold
