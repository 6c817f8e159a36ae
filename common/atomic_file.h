// Atomic output: everything is written to a temporary file beside the target
// and renamed into place only when complete, so a failed or interrupted stage
// never leaves a truncated file behind.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace docunfold {

namespace fs = std::filesystem;

// A temporary path beside `target` that keeps its extension (so encoders that
// choose a format by extension still work). Commit() renames it onto the
// target; the destructor removes it if Commit() was never reached.
class AtomicOutput {
 public:
  explicit AtomicOutput(const fs::path& target);
  ~AtomicOutput();
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  const fs::path& temp_path() const { return temp_; }
  const fs::path& target() const { return target_; }
  // Renames the temporary file onto the target; throws OutputError.
  void Commit();

 private:
  fs::path target_;
  fs::path temp_;
  bool committed_ = false;
};

// A folder beside `target`, `.<name>.tmp.<pid>.<n>`, that a stage fills and
// Commit() puts in the target's place (an earlier target is moved aside, and
// back if the rename fails); the destructor removes it if Commit() was never
// reached. Folders that killed runs left beside the target are removed first.
class AtomicDirectory {
 public:
  explicit AtomicDirectory(const fs::path& target);
  ~AtomicDirectory();
  AtomicDirectory(const AtomicDirectory&) = delete;
  AtomicDirectory& operator=(const AtomicDirectory&) = delete;

  const fs::path& path() const { return path_; }
  // Replaces the target with the folder; throws OutputError.
  void Commit();

 private:
  fs::path target_;
  fs::path path_;
  bool committed_ = false;
};

// Removes what runs that were killed (Ctrl-C, a job's time limit) left in
// `dir`: every entry named `prefix`, then the process id of a process no
// longer running, then anything but a digit. A running process's entries
// are kept (two runs at once on one machine); errors are ignored.
void RemoveLeftBehind(const fs::path& dir, const std::string& prefix);

// Creates `dir` and its parents; throws OutputError when that fails.
void EnsureDirectory(const fs::path& dir);

void WriteTextAtomic(const fs::path& path, const std::string& text);
// Writes an 8- or 16-bit image with cv::imwrite; format from the extension.
void WriteImageAtomic(const fs::path& path, const cv::Mat& image,
                      const std::vector<int>& params = {});

// Reads an image or throws InputError naming the file.
cv::Mat ReadImage(const fs::path& path, int flags = 1 /*cv::IMREAD_COLOR*/);

// Reads a whole file as it is, or throws InputError naming the file.
std::string ReadTextFile(const fs::path& path);

}  // namespace docunfold
