#include "stages/sfm/colmap_model.h"

#include <cstring>
#include <fstream>
#include <stdexcept>

namespace docunfold::sfm {

std::string CameraModelName(int model_id) {
  switch (model_id) {
    case 0:
      return "SIMPLE_PINHOLE";
    case 1:
      return "PINHOLE";
    case 2:
      return "SIMPLE_RADIAL";
    case 3:
      return "RADIAL";
  }
  throw std::invalid_argument("unsupported COLMAP camera model id " + std::to_string(model_id));
}

int CameraModelId(const std::string& name) {
  for (int id = 0; id <= 3; ++id)
    if (CameraModelName(id) == name) return id;
  return -1;
}

int CameraModelNumParams(int model_id) {
  switch (model_id) {
    case 0:
      return 3;
    case 1:
      return 4;
    case 2:
      return 4;
    case 3:
      return 5;
  }
  return -1;
}

Eigen::Matrix3d ColmapCamera::PinholeK() const {
  double fx, fy, cx, cy;
  if (model_id == 1) {
    fx = params[0], fy = params[1], cx = params[2], cy = params[3];
  } else {
    fx = fy = params[0], cx = params[1], cy = params[2];
  }
  Eigen::Matrix3d K;
  K << fx, 0, cx - 0.5, 0, fy, cy - 0.5, 0, 0, 1;
  return K;
}

double ColmapCamera::MeanFocal() const {
  return model_id == 1 ? 0.5 * (params[0] + params[1]) : params[0];
}

std::array<double, 4> ColmapCamera::OpenCvDistortion() const {
  if (model_id == 2) return {params[3], 0, 0, 0};
  if (model_id == 3) return {params[3], params[4], 0, 0};
  return {0, 0, 0, 0};
}

bool ColmapCamera::HasDistortion() const {
  for (double d : OpenCvDistortion())
    if (d != 0) return true;
  return false;
}

Eigen::Vector2d ColmapCamera::Project(const Eigen::Vector3d& x_cam) const {
  const double x = x_cam.x() / x_cam.z(), y = x_cam.y() / x_cam.z();
  const auto k = OpenCvDistortion();
  const double r2 = x * x + y * y;
  const double radial = 1 + k[0] * r2 + k[1] * r2 * r2;
  const Eigen::Matrix3d K = PinholeK();
  return {K(0, 0) * x * radial + K(0, 2), K(1, 1) * y * radial + K(1, 2)};
}

double ColmapModel::MeanReprojectionError() const {
  double sum = 0;
  size_t n = 0;
  for (const ColmapPoint& p : points) {
    sum += p.error * p.image_ids.size();
    n += p.image_ids.size();
  }
  return n ? sum / n : 0;
}

size_t ColmapModel::NumObservations() const {
  size_t n = 0;
  for (const ColmapPoint& p : points) n += p.image_ids.size();
  return n;
}

namespace {

// Little-endian binary reader that names the file when data runs out.
class BinaryReader {
 public:
  explicit BinaryReader(const fs::path& path) : path_(path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw std::runtime_error(path.string() + ": cannot open");
    data_.assign(std::istreambuf_iterator<char>(f), {});
  }
  template <typename T>
  T Read() {
    if (pos_ + sizeof(T) > data_.size())
      throw std::runtime_error(path_.string() + ": truncated at byte " + std::to_string(pos_));
    T value;
    std::memcpy(&value, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  std::string ReadString() {
    std::string s;
    for (char c; (c = Read<char>()) != '\0';) s.push_back(c);
    return s;
  }
  void Skip(size_t bytes) {
    if (pos_ + bytes > data_.size())
      throw std::runtime_error(path_.string() + ": truncated at byte " + std::to_string(pos_));
    pos_ += bytes;
  }
  // A count that cannot possibly fit in the remaining data is corruption.
  uint64_t ReadCount(size_t min_bytes_each) {
    const uint64_t n = Read<uint64_t>();
    if (min_bytes_each && n > (data_.size() - pos_) / min_bytes_each)
      throw std::runtime_error(path_.string() + ": implausible count " + std::to_string(n));
    return n;
  }
  bool AtEnd() const { return pos_ == data_.size(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  std::string data_;
  size_t pos_ = 0;
};

}  // namespace

ColmapModel ReadColmapModel(const fs::path& dir) {
  ColmapModel model;
  {
    BinaryReader r(dir / "cameras.bin");
    const uint64_t n = r.ReadCount(24);
    for (uint64_t i = 0; i < n; ++i) {
      ColmapCamera c;
      c.id = r.Read<uint32_t>();
      c.model_id = r.Read<int32_t>();
      c.width = int(r.Read<uint64_t>());
      c.height = int(r.Read<uint64_t>());
      const int np = CameraModelNumParams(c.model_id);
      if (np < 0)
        throw std::runtime_error(r.path().string() + ": unsupported camera model id " +
                                 std::to_string(c.model_id));
      for (int k = 0; k < np; ++k) c.params.push_back(r.Read<double>());
      model.cameras[c.id] = c;
    }
  }
  {
    BinaryReader r(dir / "images.bin");
    const uint64_t n = r.ReadCount(64);
    for (uint64_t i = 0; i < n; ++i) {
      ColmapImage im;
      im.id = r.Read<uint32_t>();
      const double qw = r.Read<double>(), qx = r.Read<double>(), qy = r.Read<double>(),
                   qz = r.Read<double>();
      im.q = Eigen::Quaterniond(qw, qx, qy, qz).normalized();
      for (int k = 0; k < 3; ++k) im.t[k] = r.Read<double>();
      im.camera_id = r.Read<uint32_t>();
      im.name = r.ReadString();
      im.num_points2d = r.ReadCount(24);
      for (size_t k = 0; k < im.num_points2d; ++k) {
        r.Skip(16);  // x, y
        if (r.Read<int64_t>() >= 0) ++im.num_points3d;
      }
      if (!model.cameras.count(im.camera_id))
        throw std::runtime_error(r.path().string() + ": image " + im.name +
                                 " refers to unknown camera " + std::to_string(im.camera_id));
      model.images[im.id] = im;
    }
  }
  {
    BinaryReader r(dir / "points3D.bin");
    const uint64_t n = r.ReadCount(43);
    model.points.reserve(n);
    for (uint64_t i = 0; i < n; ++i) {
      ColmapPoint p;
      p.id = r.Read<uint64_t>();
      for (int k = 0; k < 3; ++k) p.xyz[k] = r.Read<double>();
      for (int k = 0; k < 3; ++k) p.rgb[k] = r.Read<uint8_t>();
      p.error = r.Read<double>();
      const uint64_t track = r.ReadCount(8);
      for (uint64_t k = 0; k < track; ++k) {
        const uint32_t image_id = r.Read<uint32_t>();
        r.Skip(4);  // point2D_idx
        if (!model.images.count(image_id))
          throw std::runtime_error(r.path().string() + ": point " + std::to_string(p.id) +
                                   " is seen by unknown image " + std::to_string(image_id));
        p.image_ids.push_back(image_id);
      }
      model.points.push_back(std::move(p));
    }
  }
  return model;
}

}  // namespace docunfold::sfm
