#include "common/cpu_share.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <ctime>
#include <filesystem>

namespace docunfold {
namespace {

using Clock = std::chrono::steady_clock;

CpuSample Sample(double wall_seconds, double busy, double self) {
  CpuSample s;
  s.wall = Clock::time_point(
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wall_seconds)));
  s.busy_seconds = busy;
  s.self_seconds = self;
  s.valid = true;
  return s;
}

// Spins for `seconds` of wall time.
void Spin(double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  volatile double x = 0;
  while (Clock::now() < end) x = x + 1;
}

// Spins until this process has used `seconds` of CPU (or 20 times that of
// wall time), so that a loaded machine does not starve the measurement.
void SpinCpu(double seconds) {
  const std::clock_t start = std::clock();
  const auto give_up = Clock::now() + std::chrono::duration<double>(20 * seconds);
  volatile double x = 0;
  while (double(std::clock() - start) / CLOCKS_PER_SEC < seconds && Clock::now() < give_up)
    x = x + 1;
}

TEST(CpuShare, OthersAreTheBusyTimeNotSpentByThisProcess) {
  // 3 s of CPU in 2 s of wall time, 1 s of it this process's: others used 1
  // core.
  EXPECT_DOUBLE_EQ(OthersCores(Sample(10, 100, 5), Sample(12, 103, 6)), 1.0);
  // Counters are coarser than this process's own clock: never below 0.
  EXPECT_DOUBLE_EQ(OthersCores(Sample(10, 100, 5), Sample(11, 100.5, 5.9)), 0.0);
  // Unreadable /proc/stat, or no time passed: nothing known.
  CpuSample invalid = Sample(12, 103, 6);
  invalid.valid = false;
  EXPECT_DOUBLE_EQ(OthersCores(Sample(10, 100, 5), invalid), 0.0);
  EXPECT_DOUBLE_EQ(OthersCores(Sample(10, 100, 5), Sample(10, 103, 6)), 0.0);
}

TEST(CpuShare, SamplesCountThisProcessWork) {
  if (!std::filesystem::exists("/proc/stat")) GTEST_SKIP() << "no /proc/stat";
  const CpuSample before = SampleCpu();
  ASSERT_TRUE(before.valid);
  SpinCpu(0.3);
  const CpuSample after = SampleCpu();
  const double self = after.self_seconds - before.self_seconds;
  EXPECT_GT(self, 0.15);
  // The machine's busy time includes ours (jiffies: 10 ms per core).
  EXPECT_GE(after.busy_seconds - before.busy_seconds, self - 0.05);
  EXPECT_GE(AvailableCores(), 1);
}

TEST(CpuShare, SeesAnotherProcessLoad) {
  if (!std::filesystem::exists("/proc/stat")) GTEST_SKIP() << "no /proc/stat";
  CpuShare share(0.05);
  const auto start = Clock::now();
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    Spin(0.5);
    _exit(0);
  }
  int status = 0;
  rusage child_usage{};
  ASSERT_EQ(wait4(child, &status, 0, &child_usage), child);
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  const double child_cores =
      (child_usage.ru_utime.tv_sec + child_usage.ru_stime.tv_sec +
       1e-6 * (child_usage.ru_utime.tv_usec + child_usage.ru_stime.tv_usec)) /
      wall;
  const int threads = share.Threads(64);
  // Whatever else runs on this machine adds to the child's share, never less.
  EXPECT_GE(share.others(), child_cores - 0.15);
  EXPECT_GE(threads, 1);
  EXPECT_LE(threads, std::max(1, AvailableCores()));
  if (AvailableCores() <= 2 && child_cores > 0.8) {
    EXPECT_EQ(threads, 1);
  }
}

TEST(CpuShare, OneThreadAskedIsOneAndNothingMeasuredIsAllAsked) {
  CpuShare share(10.0);  // no interval long enough to measure in this test
  EXPECT_EQ(share.Threads(1), 1);
  EXPECT_EQ(share.Threads(3), 3);
  EXPECT_EQ(share.Threads(0), 1);
}

}  // namespace
}  // namespace docunfold
