#include "common/cli.h"

#include <malloc.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <opencv2/core.hpp>

#include "common/option_table.h"
#include "nlohmann/json.hpp"

namespace docunfold {

CommandLine::CommandLine(const std::string& description)
    : app_(std::make_unique<CLI::App>(description)), table_(std::make_unique<OptionTable>(*app_)) {}

CommandLine::~CommandLine() = default;

void CommandLine::Path(const std::string& name, std::filesystem::path* field,
                       const std::string& help) {
  table_->Path(name, field, help);
}

void CommandLine::RequiredPath(const std::string& name, std::filesystem::path* field,
                               const std::string& help) {
  table_->Path(name, field, help)->required();
}

void CommandLine::Text(const std::string& name, std::string* field, const std::string& help) {
  table_->Value(name, field, help);
}

Json CommandLine::Record() const { return table_->Record(); }

void LimitOpenMpThreads(char** argv) {
  if (std::getenv("OMP_THREAD_LIMIT") != nullptr) return;
  ::setenv("OMP_THREAD_LIMIT", "1", 1);
  // The program's own path, not /proc/self/exe: the process would be named
  // "exe" (in ps and top, and to pgrep and killall).
  char path[4096];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof path - 1);
  if (n <= 0) return;
  path[n] = '\0';
  ::execv(path, argv);  // returns only on failure: run as we are
}

namespace {

// glibc gives a freed buffer over 128 KB back to the kernel (mmap, or trimming
// the heap's top once the threshold adapts), and the next image of that size
// is faulted in again page by page: render spent a quarter of its time in the
// kernel. Buffers up to 32 MB (glibc's largest threshold) now come from the
// heap, which is never trimmed: a stage's memory stays at its peak until it
// exits, +4 % for render and +8 % for optimize on set01
// (docs/decisions/pipeline.md, "Freed memory kept by every stage").
void KeepFreedMemory() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
}

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

int RunStage(const std::string& program, CommandLine& command, int argc, char** argv,
             const std::function<void()>& body) {
  if (argc == 2 && std::string(argv[1]) == "--help-markdown") {
    std::cout << command.table().Markdown();
    return kExitOk;
  }
  KeepFreedMemory();
  return ParseAndRun(program, command.table().app(), argc, argv, body);
}

}  // namespace docunfold
