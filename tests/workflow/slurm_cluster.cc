#include "tests/workflow/slurm_cluster.h"

#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <random>
#include <thread>

#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

// A TCP port nothing listens on now (the kernel's choice for port 0).
int FreePort() {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t n = sizeof a;
  int port = 0;
  if (bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      getsockname(s, reinterpret_cast<sockaddr*>(&a), &n) == 0)
    port = ntohs(a.sin_port);
  close(s);
  return port;
}

bool OnPath(const std::string& program) {
  return RunCommand("command -v " + program + " > /dev/null").exit_code == 0;
}

std::string Tail(const fs::path& log) {
  return RunCommand("tail -n 3 " + Quote(log.string()) + " 2>/dev/null").output;
}

}  // namespace

SlurmCluster::SlurmCluster(const fs::path& dir) : dir_(dir) {
  if (geteuid() != 0) {
    skip_reason_ = "not root: slurmd must run as root to start jobs as their user";
    return;
  }
  for (const char* program : {"munged", "slurmctld", "slurmd", "sbatch", "scontrol", "sinfo"})
    if (!OnPath(program)) {
      skip_reason_ = std::string(program) + " is missing (Debian: slurm-wlm, munge)";
      return;
    }
  Start();
  if (!skip_reason_.empty()) Stop();
}

SlurmCluster::~SlurmCluster() { Stop(); }

std::string SlurmCluster::Environment() const {
  return "SLURM_CONF=" + Quote((dir_ / "slurm.conf").string());
}

void SlurmCluster::Start() {
  fs::create_directories(dir_ / "munge");
  fs::permissions(dir_ / "munge", fs::perms::owner_all);
  fs::create_directories(dir_ / "state");
  fs::create_directories(dir_ / "spool");
  {
    std::ofstream key(dir_ / "munge/munge.key", std::ios::binary);
    std::random_device random;
    for (int i = 0; i < 1024; ++i) key.put(char(random()));
  }
  fs::permissions(dir_ / "munge/munge.key", fs::perms::owner_read);
  const fs::path munge = dir_ / "munge";
  const CommandResult m =
      RunCommand("munged --force --key-file=" + Quote((munge / "munge.key").string()) +
                 " --socket=" + Quote((munge / "munge.socket").string()) +
                 " --pid-file=" + Quote((munge / "munged.pid").string()) +
                 " --log-file=" + Quote((munge / "munged.log").string()) +
                 " --seed-file=" + Quote((munge / "munged.seed").string()));
  if (m.exit_code != 0) {
    skip_reason_ = "munged does not start: " + m.output;
    return;
  }
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  const std::string d = dir_.string();
  std::ofstream conf(dir_ / "slurm.conf");
  conf << "ClusterName=docunfoldtest\nSlurmctldHost=" << host << "(127.0.0.1)\n"
       << "SlurmUser=root\nSlurmctldPort=" << FreePort() << "\nSlurmdPort=" << FreePort() << "\n"
       << "AuthType=auth/munge\nCredType=cred/munge\nAuthInfo=socket=" << d
       << "/munge/munge.socket\nStateSaveLocation=" << d << "/state\nSlurmdSpoolDir=" << d
       << "/spool\nSlurmctldPidFile=" << d << "/slurmctld.pid\nSlurmdPidFile=" << d
       << "/slurmd.pid\nSlurmctldLogFile=" << d << "/slurmctld.log\nSlurmdLogFile=" << d
       << "/slurmd.log\n"
       << "ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\nReturnToService=2\n"
       << "SchedulerType=sched/backfill\nSelectType=select/cons_tres\n"
       << "SelectTypeParameters=CR_CPU_Memory\nMpiDefault=none\n"
       << "JobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n"
       << "NodeName=" << host << " NodeAddr=127.0.0.1 CPUs=2 RealMemory=8000 State=UNKNOWN\n"
       << "PartitionName=batch Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n";
  conf.close();
  const std::string env = Environment() + " ";
  const std::string conf_path = Quote((dir_ / "slurm.conf").string());
  for (const char* daemon : {"slurmctld", "slurmd"}) {
    const CommandResult r = RunCommand(env + daemon + " -f " + conf_path);
    if (r.exit_code != 0) {
      skip_reason_ = std::string(daemon) + " does not start: " + r.output +
                     Tail(dir_ / (std::string(daemon) + ".log"));
      return;
    }
  }
  for (int i = 0; i < 60; ++i) {
    if (RunCommand(env + "sinfo -h -o %T").output.find("idle") != std::string::npos) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  skip_reason_ = "the Slurm node did not become idle in 30 s: " + Tail(dir_ / "slurmd.log") +
                 Tail(dir_ / "slurmctld.log");
}

void SlurmCluster::Stop() {
  for (const char* pid_file : {"slurmd.pid", "slurmctld.pid", "munge/munged.pid"}) {
    std::ifstream in(dir_ / pid_file);
    pid_t pid = 0;
    if (!(in >> pid) || pid <= 0) continue;
    kill(pid, SIGTERM);
    for (int i = 0; i < 50 && kill(pid, 0) == 0; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (kill(pid, 0) == 0) kill(pid, SIGKILL);
    std::error_code ec;
    fs::remove(dir_ / pid_file, ec);
  }
}

}  // namespace docunfold::testing
