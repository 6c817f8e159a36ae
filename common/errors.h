// Exit codes and the exceptions that map onto them. Every stage's main lets
// these propagate to RunStage (cli.h), which prints one line and exits.
#pragma once

#include <stdexcept>
#include <string>

namespace docunfold {

enum ExitCode : int {
  kExitOk = 0,
  kExitOther = 1,       // anything not covered below (a bug, a failed solver)
  kExitUsage = 2,       // bad command line
  kExitBadInput = 3,    // missing, unreadable or invalid input
  kExitCannotWrite = 4  // output cannot be written
};

// Bad command line (exit 2).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// Missing, unreadable or invalid input; the message names the file (exit 3).
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// An output file or directory cannot be written (exit 4).
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace docunfold
