// A real single-node Slurm cluster for a test: munged, slurmctld and slurmd
// started from a slurm.conf for this host written into the test's folder,
// on free ports, and stopped when the object goes, whatever happened.
#pragma once

#include <filesystem>
#include <string>

namespace docunfold::testing {

namespace fs = std::filesystem;

class SlurmCluster {
 public:
  // Starts the daemons in `dir` and waits until the node is idle. When that
  // is impossible here (not root, a program missing, a daemon that does not
  // come up), skip_reason() says why and nothing is left running.
  explicit SlurmCluster(const fs::path& dir);
  ~SlurmCluster();
  SlurmCluster(const SlurmCluster&) = delete;
  SlurmCluster& operator=(const SlurmCluster&) = delete;

  const std::string& skip_reason() const { return skip_reason_; }
  // "SLURM_CONF=<dir>/slurm.conf", for the environment of sbatch, scontrol
  // and Snakemake.
  std::string Environment() const;

 private:
  void Start();
  void Stop();

  fs::path dir_;
  std::string skip_reason_;
};

}  // namespace docunfold::testing
