#include "common/ply.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/atomic_file.h"
#include "common/errors.h"

namespace docunfold {
namespace {

const char* ScalarName(PlyScalar t) {
  switch (t) {
    case PlyScalar::kFloat32:
      return "float";
    case PlyScalar::kFloat64:
      return "double";
    case PlyScalar::kInt32:
      return "int";
    case PlyScalar::kUint32:
      return "uint";
    case PlyScalar::kUint8:
      return "uchar";
  }
  return "float";
}

bool ParseScalar(const std::string& s, PlyScalar* t, int* size) {
  struct Entry {
    const char* a;
    const char* b;
    PlyScalar t;
    int size;
  };
  static const Entry kTable[] = {{"float", "float32", PlyScalar::kFloat32, 4},
                                 {"double", "float64", PlyScalar::kFloat64, 8},
                                 {"int", "int32", PlyScalar::kInt32, 4},
                                 {"uint", "uint32", PlyScalar::kUint32, 4},
                                 {"uchar", "uint8", PlyScalar::kUint8, 1}};
  for (const Entry& e : kTable)
    if (s == e.a || s == e.b) {
      *t = e.t;
      *size = e.size;
      return true;
    }
  // Types we read but never write.
  if (s == "char" || s == "int8") {
    *t = PlyScalar::kInt32;
    *size = -1;
    return true;
  }
  if (s == "short" || s == "int16") {
    *t = PlyScalar::kInt32;
    *size = -2;
    return true;
  }
  if (s == "ushort" || s == "uint16") {
    *t = PlyScalar::kUint32;
    *size = -2;
    return true;
  }
  return false;
}

// A scalar type as it appears in a file being read: byte size and signedness.
struct FileType {
  PlyScalar t = PlyScalar::kFloat32;
  int bytes = 4;
  bool is_signed_small = false;  // char/short
};

FileType ToFileType(const std::string& name, bool* ok) {
  FileType ft;
  int size = 0;
  *ok = ParseScalar(name, &ft.t, &size);
  if (size < 0) {
    ft.bytes = -size;
    ft.is_signed_small = (name == "char" || name == "int8" || name == "short" || name == "int16");
  } else {
    ft.bytes = size;
  }
  return ft;
}

template <typename T>
T SwapIfNeeded(T v, bool swap) {
  if (!swap) return v;
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  std::memcpy(&v, b, sizeof(T));
  return v;
}

double DecodeBinary(const unsigned char* p, const FileType& ft, bool swap) {
  switch (ft.bytes) {
    case 1:
      return ft.is_signed_small ? double(*reinterpret_cast<const int8_t*>(p)) : double(*p);
    case 2: {
      uint16_t u;
      std::memcpy(&u, p, 2);
      u = SwapIfNeeded(u, swap);
      return ft.is_signed_small ? double(int16_t(u)) : double(u);
    }
    case 4: {
      uint32_t u;
      std::memcpy(&u, p, 4);
      u = SwapIfNeeded(u, swap);
      if (ft.t == PlyScalar::kFloat32) {
        float f;
        std::memcpy(&f, &u, 4);
        return f;
      }
      if (ft.t == PlyScalar::kInt32) return double(int32_t(u));
      return double(u);
    }
    default: {
      uint64_t u;
      std::memcpy(&u, p, 8);
      u = SwapIfNeeded(u, swap);
      double d;
      std::memcpy(&d, &u, 8);
      return d;
    }
  }
}

void EncodeBinary(std::string* out, double v, PlyScalar t) {
  auto put = [out](const void* p, size_t n) { out->append(static_cast<const char*>(p), n); };
  switch (t) {
    case PlyScalar::kFloat32: {
      float f = float(v);
      put(&f, 4);
      break;
    }
    case PlyScalar::kFloat64:
      put(&v, 8);
      break;
    case PlyScalar::kInt32: {
      int32_t i = int32_t(std::lround(v));
      put(&i, 4);
      break;
    }
    case PlyScalar::kUint32: {
      uint32_t i = uint32_t(std::llround(v));
      put(&i, 4);
      break;
    }
    case PlyScalar::kUint8: {
      uint8_t i = uint8_t(std::lround(v));
      put(&i, 1);
      break;
    }
  }
}

bool HostIsLittleEndian() {
  uint16_t x = 1;
  unsigned char c;
  std::memcpy(&c, &x, 1);
  return c == 1;
}

}  // namespace

const PlyProperty* PlyData::FindProperty(const std::string& name) const {
  for (const PlyProperty& p : properties)
    if (p.name == name) return &p;
  return nullptr;
}

void PlyData::SetProperty(const std::string& name, std::vector<double> values, PlyScalar type) {
  for (PlyProperty& p : properties)
    if (p.name == name) {
      p.values = std::move(values);
      p.type = type;
      return;
    }
  properties.push_back({name, type, std::move(values)});
}

std::optional<std::string> PlyData::CommentValue(const std::string& key) const {
  for (const std::string& c : comments) {
    if (c.compare(0, key.size(), key) == 0 && (c.size() == key.size() || c[key.size()] == ' '))
      return c.size() > key.size() ? c.substr(key.size() + 1) : std::string();
  }
  return std::nullopt;
}

std::optional<std::array<int, 2>> PlyData::GridSize() const {
  auto v = CommentValue("grid");
  if (!v) return std::nullopt;
  std::istringstream s(*v);
  int nx = 0, ny = 0;
  if (!(s >> nx >> ny) || nx < 2 || ny < 2 || size_t(nx) * size_t(ny) != vertices.size())
    return std::nullopt;
  return std::array<int, 2>{nx, ny};
}

void PlyData::SetGridSize(int nx, int ny) {
  for (auto it = comments.begin(); it != comments.end();)
    it = (it->rfind("grid ", 0) == 0) ? comments.erase(it) : it + 1;
  comments.push_back("grid " + std::to_string(nx) + " " + std::to_string(ny));
}

void WritePly(const fs::path& path, const PlyData& ply, PlyEncoding encoding) {
  const size_t n = ply.vertices.size();
  if (!ply.colors.empty() && ply.colors.size() != n)
    throw std::invalid_argument("WritePly: colors size differs from vertices");
  for (const PlyProperty& p : ply.properties)
    if (p.values.size() != n)
      throw std::invalid_argument("WritePly: property " + p.name + " size differs from vertices");
  for (const auto& f : ply.faces)
    for (int i : f)
      if (i < 0 || size_t(i) >= n) throw std::invalid_argument("WritePly: face index out of range");

  const bool binary = encoding == PlyEncoding::kBinary;
  std::string out;
  out += "ply\nformat ";
  out += binary ? (HostIsLittleEndian() ? "binary_little_endian" : "binary_big_endian") : "ascii";
  out += " 1.0\n";
  for (const std::string& c : ply.comments) out += "comment " + c + "\n";
  out += "element vertex " + std::to_string(n) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (!ply.colors.empty()) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  for (const PlyProperty& p : ply.properties)
    out += std::string("property ") + ScalarName(p.type) + " " + p.name + "\n";
  if (!ply.faces.empty()) {
    out += "element face " + std::to_string(ply.faces.size()) + "\n";
    out += "property list uchar int vertex_indices\n";
  }
  out += "end_header\n";

  std::ostringstream text;
  text.precision(9);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& v = ply.vertices[i];
    if (binary) {
      for (int k = 0; k < 3; ++k) EncodeBinary(&out, v[k], PlyScalar::kFloat32);
      if (!ply.colors.empty())
        for (int k = 0; k < 3; ++k) out.push_back(char(ply.colors[i][k]));
      for (const PlyProperty& p : ply.properties) EncodeBinary(&out, p.values[i], p.type);
    } else {
      text << float(v[0]) << ' ' << float(v[1]) << ' ' << float(v[2]);
      if (!ply.colors.empty())
        for (int k = 0; k < 3; ++k) text << ' ' << int(ply.colors[i][k]);
      for (const PlyProperty& p : ply.properties) {
        if (p.type == PlyScalar::kFloat32)
          text << ' ' << float(p.values[i]);
        else if (p.type == PlyScalar::kFloat64)
          text << ' ' << p.values[i];
        else
          text << ' ' << std::llround(p.values[i]);
      }
      text << '\n';
    }
  }
  for (const auto& f : ply.faces) {
    if (binary) {
      out.push_back(char(uint8_t(f.size())));
      for (int idx : f) EncodeBinary(&out, idx, PlyScalar::kInt32);
    } else {
      text << f.size();
      for (int idx : f) text << ' ' << idx;
      text << '\n';
    }
  }
  if (!binary) out += text.str();
  WriteTextAtomic(path, out);
}

namespace {

[[noreturn]] void Fail(const fs::path& path, const std::string& what) {
  throw InputError(path.string() + ": " + what);
}

// What a PLY header declares.
struct HeaderProperty {
  std::string name;
  FileType type;
  bool is_list = false;
  FileType count_type;
};
struct HeaderElement {
  std::string name;
  size_t count = 0;
  std::vector<HeaderProperty> props;
};
struct Header {
  std::vector<HeaderElement> elements;
  std::string format;
};

// A "property ..." line (after the word "property") of the last element.
HeaderProperty ReadPropertyLine(std::istringstream& s, const std::string& line,
                                const fs::path& path) {
  HeaderProperty p;
  std::string type;
  s >> type;
  bool ok = true;
  if (type == "list") {
    std::string count_type, item_type;
    s >> count_type >> item_type >> p.name;
    bool ok2 = true;
    p.is_list = true;
    p.count_type = ToFileType(count_type, &ok);
    p.type = ToFileType(item_type, &ok2);
    ok = ok && ok2;
  } else {
    s >> p.name;
    p.type = ToFileType(type, &ok);
  }
  if (!ok) Fail(path, "unsupported property type in: " + line);
  return p;
}

// The header after the "ply" line, up to and including end_header; its
// comments go to `comments`.
Header ReadHeader(std::istream& f, const fs::path& path, std::vector<std::string>* comments) {
  Header header;
  std::string line;
  while (true) {
    if (!std::getline(f, line)) Fail(path, "header ends before end_header");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream s(line);
    std::string word;
    s >> word;
    if (word == "end_header") break;
    if (word == "format") {
      s >> header.format;
    } else if (word == "comment" || word == "obj_info") {
      comments->push_back(line.size() > word.size() + 1 ? line.substr(word.size() + 1) : "");
    } else if (word == "element") {
      HeaderElement e;
      long long count = -1;
      s >> e.name >> count;
      if (count < 0) Fail(path, "bad element line: " + line);
      e.count = size_t(count);
      header.elements.push_back(e);
    } else if (word == "property") {
      if (header.elements.empty()) Fail(path, "property before any element");
      header.elements.back().props.push_back(ReadPropertyLine(s, line, path));
    } else if (!word.empty()) {
      Fail(path, "unexpected header line: " + line);
    }
  }
  return header;
}

// Reads the scalars of the body one by one, ASCII or binary.
class BodyReader {
 public:
  BodyReader(std::istream& f, const fs::path& path, bool ascii, bool swap)
      : f_(f), path_(path), ascii_(ascii), swap_(swap) {}

  double Read(const FileType& ft) {
    if (ascii_) {
      // strtod, unlike operator>>, accepts "nan" and "inf", which are then
      // reported as non-finite coordinates rather than as garbage.
      std::string token;
      if (!(f_ >> token)) Fail(path_, "truncated data");
      char* end = nullptr;
      double v = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') Fail(path_, "malformed number '" + token + "'");
      return v;
    }
    unsigned char buf[8];
    if (!f_.read(reinterpret_cast<char*>(buf), ft.bytes)) Fail(path_, "truncated data");
    return DecodeBinary(buf, ft, swap_);
  }

 private:
  std::istream& f_;
  const fs::path& path_;
  bool ascii_, swap_;
};

// The length of a list property; NaN or absurd lengths are errors, not
// undefined conversions.
size_t ReadListLength(BodyReader& body, const HeaderElement& e, const HeaderProperty& p,
                      const fs::path& path) {
  const double m = body.Read(p.count_type);
  if (!(m >= 0 && m <= 1e6)) Fail(path, "bad list length in element " + e.name);
  return static_cast<size_t>(m);
}

// The vertex element: x, y, z, optional red, green, blue, and every other
// scalar property as an extra one (lists are skipped).
void ReadVertices(const HeaderElement& e, BodyReader& body, const fs::path& path, PlyData* ply) {
  int ix = -1, iy = -1, iz = -1, ir = -1, ig = -1, ib = -1;
  std::set<std::string> names;
  for (size_t k = 0; k < e.props.size(); ++k) {
    const std::string& nm = e.props[k].name;
    // A second x would leave the first one's value nowhere to go.
    if (!names.insert(nm).second) Fail(path, "vertex property '" + nm + "' declared twice");
    if (nm == "x")
      ix = int(k);
    else if (nm == "y")
      iy = int(k);
    else if (nm == "z")
      iz = int(k);
    else if (nm == "red")
      ir = int(k);
    else if (nm == "green")
      ig = int(k);
    else if (nm == "blue")
      ib = int(k);
    else if (!e.props[k].is_list)
      ply->properties.push_back({nm, e.props[k].type.t, {}});
  }
  if (ix < 0 || iy < 0 || iz < 0) Fail(path, "vertex element lacks x, y or z");
  const bool has_color = ir >= 0 && ig >= 0 && ib >= 0;
  ply->vertices.resize(e.count);
  if (has_color) ply->colors.resize(e.count);
  for (PlyProperty& p : ply->properties) p.values.resize(e.count);
  std::vector<double> row(e.props.size());
  for (size_t i = 0; i < e.count; ++i) {
    size_t extra = 0;
    for (size_t k = 0; k < e.props.size(); ++k) {
      if (e.props[k].is_list) {
        const size_t m = ReadListLength(body, e, e.props[k], path);
        for (size_t j = 0; j < m; ++j) body.Read(e.props[k].type);
        continue;
      }
      row[k] = body.Read(e.props[k].type);
      if (int(k) != ix && int(k) != iy && int(k) != iz && int(k) != ir && int(k) != ig &&
          int(k) != ib)
        ply->properties[extra++].values[i] = row[k];
    }
    ply->vertices[i] = {row[ix], row[iy], row[iz]};
    if (!ply->vertices[i].allFinite())
      Fail(path, "vertex " + std::to_string(i) + " has a non-finite coordinate");
    if (has_color) {
      for (int c : {ir, ig, ib})
        if (!(row[c] > -1 && row[c] < 256))
          Fail(path, "vertex " + std::to_string(i) + " has a colour outside 0..255");
      ply->colors[i] = {uint8_t(row[ir]), uint8_t(row[ig]), uint8_t(row[ib])};
    }
  }
}

// Any other element: the faces' vertex_indices (or vertex_index) lists are
// kept, everything else read and dropped.
void ReadOtherElement(const HeaderElement& e, BodyReader& body, const fs::path& path,
                      PlyData* ply) {
  const bool is_face = e.name == "face";
  if (e.props.empty()) return;  // nothing to read, however many it declares
  for (size_t i = 0; i < e.count; ++i) {
    for (const HeaderProperty& p : e.props) {
      if (!p.is_list) {
        body.Read(p.type);
        continue;
      }
      const size_t m = ReadListLength(body, e, p, path);
      const bool keep = is_face && (p.name == "vertex_indices" || p.name == "vertex_index");
      std::vector<int> idx;
      for (size_t j = 0; j < m; ++j) {
        const double v = body.Read(p.type);
        // Checked as read: a NaN or huge index has no int to become.
        if (keep && !(v >= 0 && v < double(ply->vertices.size()))) {
          std::ostringstream what;
          what << "face " << i << " indexes a missing vertex " << v;
          Fail(path, what.str());
        }
        if (keep) idx.push_back(int(v));
      }
      if (keep) ply->faces.push_back(std::move(idx));
    }
  }
}

}  // namespace

PlyData ReadPly(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path.string() + ": cannot open file");
  std::string line;
  if (!std::getline(f, line) || line.rfind("ply", 0) != 0)
    Fail(path, line.empty() && f.eof() ? "empty file" : "not a PLY file");
  PlyData ply;
  const Header header = ReadHeader(f, path, &ply.comments);
  const bool ascii = header.format == "ascii";
  const bool swap = (header.format == "binary_little_endian") != HostIsLittleEndian();
  if (!ascii && header.format != "binary_little_endian" && header.format != "binary_big_endian")
    Fail(path, "unknown format '" + header.format + "'");

  // A count the rest of the file cannot hold would otherwise be allocated
  // before the data runs out.
  unsigned long long body_bytes = 0;  // stays 0 when the header ends the file
  if (f.good()) {
    const std::streampos body_start = f.tellg();
    f.seekg(0, std::ios::end);
    body_bytes = static_cast<unsigned long long>(f.tellg() - body_start);
    f.seekg(body_start);
  }
  for (const HeaderElement& e : header.elements) {
    size_t item_bytes = 0;  // at least, per item (ASCII: one character per value)
    for (const HeaderProperty& p : e.props)
      item_bytes += ascii ? 1 : (p.is_list ? p.count_type.bytes : p.type.bytes);
    if (item_bytes > 0 && e.count > body_bytes / item_bytes)
      Fail(path, "element " + e.name + " declares " + std::to_string(e.count) +
                     " items, more than the file's " + std::to_string(body_bytes) +
                     " bytes of data can hold");
  }

  BodyReader body(f, path, ascii, swap);
  for (const HeaderElement& e : header.elements) {
    if (e.name == "vertex")
      ReadVertices(e, body, path, &ply);
    else
      ReadOtherElement(e, body, path, &ply);
  }
  return ply;
}

}  // namespace docunfold
