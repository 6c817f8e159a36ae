// Command-line plumbing shared by every stage's main: parsing with CLI11
// into an options struct, and exception-to-exit-code mapping.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "common/errors.h"
#include "common/json_io.h"
#include "common/option_table_fwd.h"
#include "common/program.h"

namespace CLI {
class App;
}  // namespace CLI

namespace docunfold {

// A stage's command line: its description, the paths its main declares, and
// the options the stage declares on table(). The mains see no CLI11: its
// header costs each of them about 6 s to compile.
class CommandLine {
 public:
  explicit CommandLine(const std::string& description);
  ~CommandLine();
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;

  OptionTable& table() { return *table_; }

  // --name PATH, an input or output (not recorded); the stage cannot run
  // without a required one.
  void Path(const std::string& name, std::filesystem::path* field, const std::string& help);
  void RequiredPath(const std::string& name, std::filesystem::path* field, const std::string& help);
  // --name TEXT into *field, recorded.
  void Text(const std::string& name, std::string* field, const std::string& help);

  // Every recorded option's current value (OptionTable::Record).
  Json Record() const;

 private:
  std::unique_ptr<CLI::App> app_;
  std::unique_ptr<OptionTable> table_;
};

// Parses the command line into the fields `command` declared, runs `body`
// and maps what it throws to an exit code, printing exactly one line
// "<program>: <kind>: <message>" to stderr. CLI11 parse errors become exit 2
// (or 0 for --help / --version). `--help-markdown` prints the options' table
// for docs/stages/ instead. Before `body`, malloc is set to keep the memory
// the stage frees, instead of giving it back to the kernel (cli.cc).
int RunStage(const std::string& program, CommandLine& command, int argc, char** argv,
             const std::function<void()>& body);

// For programs that use Tesseract: its OpenMP parallelism (up to 10 threads
// per region) spins on few shared cores and makes OCR several times slower.
// libgomp reads OMP_THREAD_LIMIT only when it is loaded, so when the variable
// is unset this sets it to 1 and re-executes the program once (call first
// thing in main; returns normally when nothing needs doing or exec fails).
void LimitOpenMpThreads(char** argv);

}  // namespace docunfold
