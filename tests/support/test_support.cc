#include "tests/support/test_support.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/errors.h"

namespace docunfold::testing {

TempDir::TempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "docunfold";
  for (char& c : name)
    if (c == '/') c = '_';
  std::random_device rd;
  path_ = fs::temp_directory_path() / ("docunfold-test-" + name + "-" + std::to_string(rd()));
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  if (std::getenv("DOCUNFOLD_KEEP_TEST_DIRS")) return;
  std::error_code ec;
  fs::remove_all(path_, ec);
}

std::string ReadFileText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

CommandResult RunCommand(const std::string& command_line) {
  CommandResult result;
  FILE* pipe = ::popen((command_line + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) result.output.append(buf.data(), n);
  int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

fs::path StageBinary(const std::string& name) { return fs::path(DOCUNFOLD_BIN_DIR) / name; }
fs::path SourceDir() { return fs::path(DOCUNFOLD_SOURCE_DIR); }
fs::path SampleDir(const std::string& name) { return SourceDir() / "samples" / name; }
namespace {

// $env when set, else ../shared/<name> beside the source tree when it is
// there, else "".
fs::path SharedSets(const char* env, const char* name) {
  if (const char* value = std::getenv(env)) return value;
  fs::path p = SourceDir().parent_path() / "shared" / name;
  std::error_code ec;
  return fs::is_directory(p, ec) ? p : fs::path();
}

}  // namespace

fs::path RealisticDir() { return SharedSets("DOCUNFOLD_REALISTIC_DIR", "realistic"); }
fs::path RealisticHardDir() { return SharedSets("DOCUNFOLD_REALISTIC_HARD_DIR", "realistic-hard"); }

fs::path E2eDir() { return fs::path(DOCUNFOLD_BIN_DIR).parent_path() / "e2e"; }

std::map<std::string, Json> E2eRows(const std::string& set) {
  std::map<std::string, Json> rows;
  const Json results = ReadJsonFile(E2eDir() / "results.json");
  for (const Json& s : results.at("sets")) {
    if (s.value("name", "") != set) continue;
    for (const Json& r : s.at("rows"))
      if (r.value("status", "") == "ok" && r.contains("metrics") && r["metrics"].is_object())
        rows[r.at("method").get<std::string>()] = r["metrics"];
  }
  return rows;
}

double Metric(const std::map<std::string, Json>& rows, const std::string& method,
              const std::string& key) {
  auto it = rows.find(method);
  if (it == rows.end() || !it->second.contains(key) || !it->second[key].is_number()) return NAN;
  return it->second[key].get<double>();
}

std::string Quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

cv::Mat1f Detail(const cv::Mat& image) {
  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else
    grey = image;
  cv::Mat1f f, low;
  grey.convertTo(f, CV_32F);
  cv::GaussianBlur(f, low, cv::Size(0, 0), 6);
  return f / (low + 10.0f) - 1.0f;
}

double Correlation(const cv::Mat1f& a, const cv::Mat1f& b, const cv::Mat1b& mask) {
  cv::Scalar ma, sa, mb, sb;
  cv::meanStdDev(a, ma, sa, mask);
  cv::meanStdDev(b, mb, sb, mask);
  cv::Mat1f prod = (a - ma[0]).mul(b - mb[0]);
  return cv::mean(prod, mask)[0] / (sa[0] * sb[0] + 1e-12);
}

}  // namespace docunfold::testing
