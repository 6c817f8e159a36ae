// JSON files with the self-describing header every docunfold file carries:
// {"format": "docunfold.<name>", "version": <int>, "producer": {...}}.
// Readers report problems as "<file>:<json pointer>: <what is wrong>".
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace docunfold {

using Json = nlohmann::json;
namespace fs = std::filesystem;

// Header fields for a file written by `stage` with the given options.
Json MakeHeader(const std::string& format, int version, const std::string& stage,
                const Json& options = Json::object());

// Parses a JSON file; throws InputError on a missing or malformed file.
Json ReadJsonFile(const fs::path& path);

// Checks "format" and that "version" is an integer <= max_version.
void CheckFormat(const Json& doc, const fs::path& path, const std::string& format, int max_version);

// Writes pretty JSON atomically (throws OutputError).
void WriteJsonAtomic(const fs::path& path, const Json& doc);

// Typed access that throws InputError "<file>:<pointer>: <problem>".
class JsonReader {
 public:
  JsonReader(const Json& doc, fs::path file) : doc_(doc), file_(std::move(file)) {}

  const Json& At(const std::string& pointer) const;
  bool Has(const std::string& pointer) const;
  double Number(const std::string& pointer) const;
  int Integer(const std::string& pointer) const;
  std::string String(const std::string& pointer) const;
  Eigen::Matrix3d Matrix3(const std::string& pointer) const;
  Eigen::Vector3d Vector3(const std::string& pointer) const;
  // [x, y], both finite numbers.
  Eigen::Vector2d Vector2(const std::string& pointer) const;
  // An array of at least `min_points` [x, y] (a polyline).
  std::vector<Eigen::Vector2d> Points(const std::string& pointer, size_t min_points) const;
  // Throws InputError for `pointer` with the given problem.
  [[noreturn]] void Fail(const std::string& pointer, const std::string& problem) const;
  const fs::path& file() const { return file_; }

 private:
  const Json& doc_;
  fs::path file_;
};

// `v`, or null where it is NaN or infinite (JSON has neither).
Json NumberOrNull(double v);

Json ToJson(const Eigen::Matrix3d& m);
Json ToJson(const Eigen::Vector3d& v);

}  // namespace docunfold
