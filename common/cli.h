// Command-line plumbing shared by every stage's main: parsing with CLI11
// into an options struct, and exception-to-exit-code mapping.
#pragma once

#include <functional>
#include <string>

#include "common/errors.h"
#include "common/option_table.h"
#include "common/program.h"

namespace docunfold {

// Parses the command line into `options`' fields, runs `body` and maps what
// it throws to an exit code, printing exactly one line
// "<program>: <kind>: <message>" to stderr. CLI11 parse errors become exit 2
// (or 0 for --help / --version). `--help-markdown` prints the options' table
// for docs/stages/ instead. Before `body`, malloc is set to keep the memory
// the stage frees, instead of giving it back to the kernel (cli.cc).
int RunStage(const std::string& program, OptionTable& options, int argc, char** argv,
             const std::function<void()>& body);

// For programs that use Tesseract: its OpenMP parallelism (up to 10 threads
// per region) spins on few shared cores and makes OCR several times slower.
// libgomp reads OMP_THREAD_LIMIT only when it is loaded, so when the variable
// is unset this sets it to 1 and re-executes the program once (call first
// thing in main; returns normally when nothing needs doing or exec fails).
void LimitOpenMpThreads(char** argv);

}  // namespace docunfold
