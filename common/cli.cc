#include "common/cli.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <opencv2/core.hpp>

#include "nlohmann/json.hpp"

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

void LimitOpenMpThreads(char** argv) {
  if (std::getenv("OMP_THREAD_LIMIT") != nullptr) return;
  ::setenv("OMP_THREAD_LIMIT", "1", 1);
  ::execv("/proc/self/exe", argv);  // returns only on failure: run as we are
}

void Log(const std::string& message) { std::cerr << ProgramName() << ": " << message << std::endl; }

namespace {

int ParseAndRun(const std::string& program, CLI::App& app, int argc, char** argv,
                const std::function<void()>& body) {
  SetProgramName(program);
  app.set_version_flag("--version", std::string(ProgramVersion()));
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return kExitOk;
  } catch (const CLI::CallForAllHelp&) {
    std::cout << app.help("", CLI::AppFormatMode::All);
    return kExitOk;
  } catch (const CLI::CallForVersion&) {
    std::cout << program << " " << ProgramVersion() << "\n";
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    std::cerr << program << ": usage error: " << e.what() << " (see --help)" << std::endl;
    return kExitUsage;
  }
  auto fail = [&](int code, const char* kind, const std::string& what) {
    std::cerr << program << ": " << kind << ": " << what << std::endl;
    return code;
  };
  try {
    body();
    return kExitOk;
  } catch (const UsageError& e) {
    return fail(kExitUsage, "usage error", e.what());
  } catch (const InputError& e) {
    return fail(kExitBadInput, "bad input", e.what());
  } catch (const OutputError& e) {
    return fail(kExitCannotWrite, "cannot write output", e.what());
  } catch (const nlohmann::json::exception& e) {
    return fail(kExitBadInput, "bad input", e.what());
  } catch (const cv::Exception& e) {
    return fail(kExitOther, "error", e.what());
  } catch (const std::bad_alloc&) {
    return fail(kExitOther, "error", "out of memory");
  } catch (const std::exception& e) {
    return fail(kExitOther, "error", e.what());
  }
}

}  // namespace

int RunStage(const std::string& program, OptionTable& options, int argc, char** argv,
             const std::function<void()>& body) {
  if (argc == 2 && std::string(argv[1]) == "--help-markdown") {
    std::cout << options.Markdown();
    return kExitOk;
  }
  return ParseAndRun(program, options.app(), argc, argv, body);
}

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
