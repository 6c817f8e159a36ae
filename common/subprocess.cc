#include "common/subprocess.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "common/errors.h"

namespace docunfold {

fs::path FindExecutable(const std::string& program) {
  if (program.empty()) return {};
  auto executable = [](const fs::path& p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
  };
  if (program.find('/') != std::string::npos)
    return executable(program) ? fs::path(program) : fs::path();
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/local/bin:/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    fs::path candidate = fs::path(dir.empty() ? "." : dir) / program;
    if (executable(candidate)) return candidate;
  }
  return {};
}

SubprocessResult RunSubprocess(const std::vector<std::string>& argv,
                               const SubprocessOptions& options) {
  SubprocessResult result;
  const auto start = std::chrono::steady_clock::now();
  const bool logging = !options.log_file.empty();
  std::ofstream log;
  if (logging) log.open(options.log_file, std::ios::app);
  if (logging && !log) throw OutputError(options.log_file.string() + ": cannot write log file");
  const fs::path exe = FindExecutable(argv.at(0));
  if (exe.empty()) {
    result.not_found = true;
    return result;
  }
  log << "$";
  for (const std::string& a : argv) log << " " << a;
  log << "\n" << std::flush;

  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  }
  if (pid == 0) {
    // Child: own process group (so a timeout kills COLMAP's helpers too),
    // both output streams into the pipe, stdin from /dev/null.
    ::setpgid(0, 0);
    // Dies with us (a killed test or stage must not leave COLMAP running).
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    ::dup2(fds[1], STDOUT_FILENO);
    ::dup2(fds[1], STDERR_FILENO);
    ::close(fds[0]);
    ::close(fds[1]);
    const int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) ::dup2(devnull, STDIN_FILENO);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(exe.c_str(), args.data());
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also from the parent, to avoid racing the child
  ::close(fds[1]);

  std::string pending;
  auto flush_lines = [&](bool all) {
    size_t begin = 0;
    for (size_t nl; (nl = pending.find('\n', begin)) != std::string::npos; begin = nl + 1) {
      std::string line = pending.substr(begin, nl - begin);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (options.on_line) options.on_line(line);
    }
    pending.erase(0, begin);
    if (all && !pending.empty()) {
      if (options.on_line) options.on_line(pending);
      pending.clear();
    }
  };
  char buf[8192];
  bool open = true;
  while (open) {
    int wait_ms = 1000;
    if (options.timeout_seconds > 0) {
      const double left =
          options.timeout_seconds -
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (left <= 0) {
        result.timed_out = true;
        ::kill(-pid, SIGKILL);
        break;
      }
      wait_ms = std::max(1, std::min(1000, int(left * 1000)));
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, wait_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      open = false;
      break;
    }
    log.write(buf, n);
    pending.append(buf, size_t(n));
    flush_lines(false);
  }
  flush_lines(true);
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) {
    result.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    result.signal = WTERMSIG(status);
  }
  if (result.exit_code == 127 && !result.timed_out) {
    // execv failed in the child (e.g. permissions changed under us).
    result.not_found = true;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  log << "# exit " << result.exit_code;
  if (result.signal) log << " (signal " << result.signal << ")";
  if (result.timed_out) log << " (killed after the time limit)";
  log << ", " << result.seconds << " s\n";
  if (logging && !log) throw OutputError(options.log_file.string() + ": write failed");
  return result;
}

}  // namespace docunfold
