#include "common/json_io.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/program.h"

namespace docunfold {

Json MakeHeader(const std::string& format, int version, const std::string& stage,
                const Json& options) {
  Json header;
  header["format"] = format;
  header["version"] = version;
  header["producer"] = {{"program", "docunfold"},
                        {"stage", stage},
                        {"version", ProgramVersion()},
                        {"options", options}};
  return header;
}

Json ReadJsonFile(const fs::path& path) {
  std::ifstream f(path);
  if (!f) throw InputError(path.string() + ": cannot open file");
  std::stringstream buffer;
  buffer << f.rdbuf();
  if (buffer.str().find_first_not_of(" \t\r\n") == std::string::npos)
    throw InputError(path.string() + ": empty file");
  try {
    return Json::parse(buffer.str());
  } catch (const Json::parse_error& e) {
    throw InputError(path.string() + ": not valid JSON (byte " + std::to_string(e.byte) + ")");
  }
}

void CheckFormat(const Json& doc, const fs::path& path, const std::string& format,
                 int max_version) {
  JsonReader r(doc, path);
  if (!doc.is_object()) r.Fail("", "expected a JSON object");
  std::string found = r.String("/format");
  if (found != format) r.Fail("/format", "expected \"" + format + "\", found \"" + found + "\"");
  int version = r.Integer("/version");
  if (version < 1 || version > max_version)
    r.Fail("/version", "unsupported version " + std::to_string(version) +
                           " (this program reads up to " + std::to_string(max_version) + ")");
}

void WriteJsonAtomic(const fs::path& path, const Json& doc) {
  WriteTextAtomic(path, doc.dump(1) + "\n");
}

void JsonReader::Fail(const std::string& pointer, const std::string& problem) const {
  throw InputError(file_.string() + ":" + (pointer.empty() ? "/" : pointer) + ": " + problem);
}

bool JsonReader::Has(const std::string& pointer) const {
  return doc_.contains(Json::json_pointer(pointer));
}

const Json& JsonReader::At(const std::string& pointer) const {
  Json::json_pointer p(pointer);
  if (!doc_.contains(p)) Fail(pointer, "missing");
  return doc_.at(p);
}

double JsonReader::Number(const std::string& pointer) const {
  const Json& v = At(pointer);
  if (!v.is_number()) Fail(pointer, "expected a number");
  double d = v.get<double>();
  if (!std::isfinite(d)) Fail(pointer, "not a finite number");
  return d;
}

int JsonReader::Integer(const std::string& pointer) const {
  const Json& v = At(pointer);
  if (!v.is_number_integer()) Fail(pointer, "expected an integer");
  return v.get<int>();
}

std::string JsonReader::String(const std::string& pointer) const {
  const Json& v = At(pointer);
  if (!v.is_string()) Fail(pointer, "expected a string");
  return v.get<std::string>();
}

Eigen::Matrix3d JsonReader::Matrix3(const std::string& pointer) const {
  const Json& v = At(pointer);
  if (!v.is_array() || v.size() != 3) Fail(pointer, "expected a 3x3 array");
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i) {
    std::string row = pointer + "/" + std::to_string(i);
    if (!v[i].is_array() || v[i].size() != 3) Fail(row, "expected 3 numbers");
    for (int j = 0; j < 3; ++j) m(i, j) = Number(row + "/" + std::to_string(j));
  }
  return m;
}

Eigen::Vector3d JsonReader::Vector3(const std::string& pointer) const {
  const Json& v = At(pointer);
  if (!v.is_array() || v.size() != 3) Fail(pointer, "expected 3 numbers");
  Eigen::Vector3d x;
  for (int i = 0; i < 3; ++i) x[i] = Number(pointer + "/" + std::to_string(i));
  return x;
}

Eigen::Vector2d JsonReader::Vector2(const std::string& pointer) const {
  const Json& p = At(pointer);
  if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
    Fail(pointer, "expected [x, y]");
  const Eigen::Vector2d v(p[0].get<double>(), p[1].get<double>());
  if (!v.allFinite()) Fail(pointer, "not finite");
  return v;
}

std::vector<Eigen::Vector2d> JsonReader::Points(const std::string& pointer,
                                                size_t min_points) const {
  const Json& points = At(pointer);
  if (!points.is_array() || points.size() < min_points)
    Fail(pointer, "expected at least " + std::to_string(min_points) + " points");
  std::vector<Eigen::Vector2d> out;
  for (size_t k = 0; k < points.size(); ++k)
    out.push_back(Vector2(pointer + "/" + std::to_string(k)));
  return out;
}

Json NumberOrNull(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json ToJson(const Eigen::Matrix3d& m) {
  Json a = Json::array();
  for (int i = 0; i < 3; ++i) a.push_back({m(i, 0), m(i, 1), m(i, 2)});
  return a;
}

Json ToJson(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

}  // namespace docunfold
