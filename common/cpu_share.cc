#include "common/cpu_share.h"

#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace docunfold {
namespace {

// The CPUs this process may run on; false when the kernel does not say.
bool Affinity(cpu_set_t* set) {
  CPU_ZERO(set);
  return sched_getaffinity(0, sizeof(*set), set) == 0;
}

bool InAffinity(int cpu, const cpu_set_t& set) {
  return cpu >= 0 && cpu < CPU_SETSIZE && CPU_ISSET(cpu, &set);
}

}  // namespace

int AvailableCores() {
  cpu_set_t set;
  if (!Affinity(&set)) return 1;
  return std::max(1, CPU_COUNT(&set));
}

CpuSample SampleCpu() {
  CpuSample s;
  s.wall = std::chrono::steady_clock::now();
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) == 0)
    s.self_seconds = usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
                     1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  cpu_set_t set;
  const bool have_set = Affinity(&set);
  const long ticks_per_second = sysconf(_SC_CLK_TCK);
  std::ifstream in("/proc/stat");
  if (!in || ticks_per_second <= 0) return s;
  std::string line;
  double ticks = 0;
  int cpus = 0;
  while (std::getline(in, line)) {
    // Per-CPU lines "cpuN user nice system idle iowait irq softirq steal ...";
    // the aggregate "cpu " line would count cores this process cannot use.
    if (line.compare(0, 3, "cpu") != 0 || line.size() < 4 || !std::isdigit(line[3])) continue;
    std::istringstream fields(line.substr(3));
    int cpu = -1;
    double user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
    fields >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal;
    if (cpu < 0) continue;
    if (have_set && !InAffinity(cpu, set)) continue;
    ticks += user + nice + system + irq + softirq + steal;
    ++cpus;
  }
  if (cpus == 0) return s;
  s.busy_seconds = ticks / double(ticks_per_second);
  s.valid = true;
  return s;
}

double OthersCores(const CpuSample& before, const CpuSample& after) {
  const double wall = std::chrono::duration<double>(after.wall - before.wall).count();
  if (!before.valid || !after.valid || wall <= 0) return 0;
  const double others =
      (after.busy_seconds - before.busy_seconds) - (after.self_seconds - before.self_seconds);
  return std::max(0.0, others / wall);
}

CpuShare::CpuShare(double min_interval_seconds)
    : min_interval_(min_interval_seconds), cores_(AvailableCores()), last_(SampleCpu()) {}

int CpuShare::Threads(int wanted) {
  wanted = std::max(1, wanted);
  if (wanted == 1) return 1;
  const CpuSample now = SampleCpu();
  if (!now.valid) return wanted;
  if (!last_.valid) {
    last_ = now;
    return wanted;
  }
  if (std::chrono::duration<double>(now.wall - last_.wall).count() >= min_interval_) {
    others_ = OthersCores(last_, now);
    last_ = now;
    measured_ = true;
  }
  if (!measured_) return wanted;
  return std::clamp(int(std::lround(cores_ - others_)), 1, wanted);
}

}  // namespace docunfold
