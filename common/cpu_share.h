// How many threads a process should run now, judged from what the rest of
// the machine is doing (Linux /proc/stat), so parallel loops with barriers
// (the solver's conjugate gradients) use both cores when they are free and
// fall back to one as soon as other work competes for them.
//
// Why not OpenMP's dynamic threads: libgomp's omp_set_dynamic decides from
// the 15-minute load average, which in a pipeline still counts the stages
// that ran before (sfm keeps both cores busy) and so held optimize to one
// thread on an idle machine (set05: 8.7 s instead of 6.5 s). Why not always
// all cores: two processes spinning at each other's barriers took 15 s each
// where one thread each takes 8.5 s.
#pragma once

#include <chrono>

namespace docunfold {

// CPU time counters of the cores this process may run on.
struct CpuSample {
  std::chrono::steady_clock::time_point wall;
  double busy_seconds = 0;  // all processes: user+nice+system+irq+softirq+steal
  double self_seconds = 0;  // this process, all threads (user+system)
  bool valid = false;       // /proc/stat was readable
};

// Reads the counters now (busy_seconds summed over the CPUs in this
// process's affinity mask).
CpuSample SampleCpu();

// Cores used by other processes between two samples, averaged over the
// wall time between them (>= 0).
double OthersCores(const CpuSample& before, const CpuSample& after);

// Cores in this process's affinity mask (what `nproc` prints), >= 1.
int AvailableCores();

// Decides a thread count per stretch of work from the CPU other processes
// used since the previous measurement: round(cores - others), clamped to
// [1, wanted]. Before anything is measured, and without /proc/stat, the
// answer is `wanted`. A measurement needs at least `min_interval_seconds`
// since the previous one (jiffies are 10 ms: shorter ones are noise);
// calls in between reuse the last estimate.
class CpuShare {
 public:
  explicit CpuShare(double min_interval_seconds = 0.05);
  int Threads(int wanted);
  // Other processes' load at the last measurement, in cores.
  double others() const { return others_; }

 private:
  double min_interval_;
  int cores_;
  CpuSample last_;
  bool measured_ = false;
  double others_ = 0;
};

}  // namespace docunfold
