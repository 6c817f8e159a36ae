#include "common/atomic_file.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>

#include "common/errors.h"

namespace docunfold {

AtomicOutput::AtomicOutput(const fs::path& target) : target_(target) {
  EnsureDirectory(target.has_parent_path() ? target.parent_path() : fs::path("."));
  const std::string prefix = "." + target.stem().string() + ".tmp.";
  RemoveLeftBehind(target.parent_path(), prefix);
  temp_ = target;
  temp_.replace_filename(prefix + std::to_string(::getpid()) + target.extension().string());
}

AtomicOutput::~AtomicOutput() {
  if (!committed_) {
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

void AtomicOutput::Commit() {
  std::error_code ec;
  if (!fs::exists(temp_, ec)) throw OutputError(target_.string() + ": nothing was written");
  fs::rename(temp_, target_, ec);
  if (ec) throw OutputError(target_.string() + ": cannot rename temporary file: " + ec.message());
  committed_ = true;
}

AtomicDirectory::AtomicDirectory(const fs::path& target)
    : target_(fs::absolute(target).lexically_normal()) {
  if (target_.filename().empty()) target_ = target_.parent_path();  // "out/" names out
  const fs::path parent = target_.parent_path();
  EnsureDirectory(parent);
  const std::string prefix = "." + target_.filename().string() + ".tmp.";
  RemoveLeftBehind(parent, prefix);
  static std::atomic<int> made{0};
  path_ = parent / (prefix + std::to_string(::getpid()) + "." + std::to_string(++made));
  std::error_code ec;
  fs::remove_all(path_, ec);
  fs::create_directories(path_, ec);
  if (ec) throw OutputError(path_.string() + ": cannot create: " + ec.message());
}

AtomicDirectory::~AtomicDirectory() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(path_, ec);
}

void AtomicDirectory::Commit() {
  std::error_code ec;
  fs::path old;
  if (fs::exists(target_, ec)) {
    old = path_;
    old += ".old";
    fs::remove_all(old, ec);
    fs::rename(target_, old, ec);
    if (ec)
      throw OutputError(target_.string() + ": cannot move the old output aside: " + ec.message());
  }
  fs::rename(path_, target_, ec);
  if (ec) {
    std::error_code ignored;
    if (!old.empty()) fs::rename(old, target_, ignored);
    throw OutputError(target_.string() + ": cannot rename into place: " + ec.message());
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
}

namespace {

// Whether process `pid` may still write: it exists and is not a zombie (one
// killed and not yet reaped by its parent, which keeps its id for a while).
bool StillRuns(pid_t pid) {
  if (::kill(pid, 0) != 0 && errno == ESRCH) return false;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  const std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const size_t name_end = text.rfind(')');  // the state follows the program's name
  return name_end == std::string::npos || name_end + 2 >= text.size() || text[name_end + 2] != 'Z';
}

}  // namespace

void RemoveLeftBehind(const fs::path& dir, const std::string& prefix) {
  std::error_code ec;
  for (fs::directory_iterator it(dir.empty() ? fs::path(".") : dir, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    size_t digits = prefix.size();
    while (digits < name.size() && std::isdigit(static_cast<unsigned char>(name[digits]))) ++digits;
    if (digits == prefix.size() || digits - prefix.size() > 9) continue;
    const auto pid = pid_t(std::stol(name.substr(prefix.size(), digits - prefix.size())));
    if (pid <= 0 || pid == ::getpid() || StillRuns(pid)) continue;
    std::error_code ignored;
    fs::remove_all(it->path(), ignored);
  }
}

void EnsureDirectory(const fs::path& dir) {
  std::error_code ec;
  if (dir.empty()) return;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw OutputError(dir.string() + ": cannot create directory" +
                      (ec ? ": " + ec.message() : std::string()));
}

void WriteTextAtomic(const fs::path& path, const std::string& text) {
  AtomicOutput out(path);
  {
    std::ofstream f(out.temp_path(), std::ios::binary);
    f << text;
    f.close();
    if (!f) throw OutputError(path.string() + ": write failed");
  }
  out.Commit();
}

void WriteImageAtomic(const fs::path& path, const cv::Mat& image, const std::vector<int>& params) {
  if (image.empty()) throw OutputError(path.string() + ": empty image");
  AtomicOutput out(path);
  bool ok = false;
  try {
    ok = cv::imwrite(out.temp_path().string(), image, params);
  } catch (const cv::Exception& e) {
    throw OutputError(path.string() + ": " + e.what());
  }
  if (!ok) throw OutputError(path.string() + ": cannot encode or write image");
  out.Commit();
}

cv::Mat ReadImage(const fs::path& path, int flags) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path.string() + ": no such file");
  cv::Mat image;
  try {
    image = cv::imread(path.string(), flags);
  } catch (const cv::Exception&) {
  }
  if (image.empty()) throw InputError(path.string() + ": not a readable image");
  return image;
}

std::string ReadTextFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open file");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace docunfold
