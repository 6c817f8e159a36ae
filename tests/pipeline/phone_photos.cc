#include "tests/pipeline/phone_photos.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "common/json_io.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {

namespace {

// Names as messaging apps, scanners and people give them.
const char* const kSpacedNames[] = {"Photo 2026-11-28 10.15.jpg", "vue été 2.jpg",
                                    "IMG 0003 (copie).jpg", "Scan – page 1.jpg", "naïve ñ 5.jpg"};

void Run(const std::string& command) {
  if (std::system((command + " > /dev/null 2>&1").c_str()) != 0)
    throw std::runtime_error(command + ": failed (scripts/install-deps.sh installs the tools)");
}

// A true camera after its photo changed: pixels (edges at 0) map by `B`,
// the camera frame turns by `Q` about the optical axis.
void Transform(const Eigen::Matrix3d& B, const Eigen::Matrix3d& Q, int width, int height,
               Json* view) {
  const JsonReader read(*view, "ground_truth/cameras.json");
  Eigen::Matrix3d K = read.Matrix3("/K");
  K(0, 2) += 0.5;
  K(1, 2) += 0.5;
  K = B * K * Q.transpose();
  K(0, 2) -= 0.5;
  K(1, 2) -= 0.5;
  const Eigen::Matrix3d R = Q * read.Matrix3("/R");
  const Eigen::Vector3d t = Q * read.Vector3("/t");
  (*view)["K"] = ToJson(K);
  (*view)["R"] = ToJson(R);
  (*view)["t"] = ToJson(t);
  (*view)["width"] = width;
  (*view)["height"] = height;
}

// The photo turned 90° clockwise: (x, y) -> (H - y, x).
void TurnClockwise(Json* view) {
  const int w = view->at("width").get<int>(), h = view->at("height").get<int>();
  Eigen::Matrix3d B, Q;
  B << 0, -1, h, 1, 0, 0, 0, 0, 1;
  Q << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  Transform(B, Q, h, w, view);
}

void Scale(int new_width, int new_height, Json* view) {
  const double sx = double(new_width) / view->at("width").get<int>();
  const double sy = double(new_height) / view->at("height").get<int>();
  Eigen::Matrix3d B = Eigen::Matrix3d::Identity();
  B(0, 0) = sx;
  B(1, 1) = sy;
  Transform(B, Eigen::Matrix3d::Identity(), new_width, new_height, view);
}

Json* FindView(Json* cameras, const std::string& image) {
  if (!cameras) return nullptr;
  for (Json& v : cameras->at("views"))
    if (v.value("image", "") == image) return &v;
  return nullptr;
}

}  // namespace

void MakePhoneSet(const fs::path& from, const fs::path& to, const PhoneChanges& changes) {
  fs::create_directories(to / "images");
  std::vector<fs::path> photos;
  for (const auto& e : fs::directory_iterator(from / "images")) photos.push_back(e.path());
  std::sort(photos.begin(), photos.end());
  Json cameras;
  const bool truth = fs::is_directory(from / "ground_truth");
  if (truth) {
    fs::copy(from / "ground_truth", to / "ground_truth", fs::copy_options::recursive);
    cameras = ReadJsonFile(to / "ground_truth/cameras.json");
  }
  for (int i = 0; i < int(photos.size()); ++i) {
    const std::string original = photos[i].filename().string();
    Json* view = FindView(truth ? &cameras : nullptr, original);
    std::string name = changes.spaced_names && i < 5 ? kSpacedNames[i] : original;
    fs::path out = to / "images" / name;
    const bool redraw = changes.scale.count(i) || changes.turned.count(i);
    if (!redraw) {
      fs::copy_file(photos[i], out);
    } else {
      cv::Mat image = cv::imread(photos[i].string(), cv::IMREAD_COLOR);
      if (changes.scale.count(i)) {
        const double f = changes.scale.at(i);
        cv::resize(image, image, cv::Size(), f, f, f < 1 ? cv::INTER_AREA : cv::INTER_CUBIC);
        if (view) Scale(image.cols, image.rows, view);
      }
      if (changes.turned.count(i)) {
        cv::rotate(image, image, cv::ROTATE_90_CLOCKWISE);
        if (view) TurnClockwise(view);
      }
      cv::imwrite(out.string(), image, {cv::IMWRITE_JPEG_QUALITY, 95});
    }
    if (changes.exif_portrait.count(i)) {
      std::string focal;
      if (view) {
        const double f = view->at("K").at(0).at(0).get<double>();
        const double diagonal =
            std::hypot(view->at("width").get<double>(), view->at("height").get<double>());
        focal = " -FocalLengthIn35mmFormat=" +
                std::to_string(int(std::lround(f * std::hypot(36.0, 24.0) / diagonal)));
        TurnClockwise(view);
      }
      Run("exiftool -n -overwrite_original -Orientation=6 -Make=docunfold -Model='synth phone'" +
          focal + " " + Quote(out.string()));
    }
    if (changes.heic.count(i)) {
      const fs::path heic = fs::path(out).replace_extension(".heic");
      // x265's fastest preset: 0.4 s a photo instead of 3 s, and a HEIC file
      // all the same (what the reader is tested on).
      Run("heif-enc -q 92 -p preset=ultrafast " + Quote(out.string()) + " -o " +
          Quote(heic.string()));
      fs::remove(out);
      out = heic;
      name = heic.filename().string();
    }
    if (changes.truncated.count(i)) fs::resize_file(out, fs::file_size(out) * 6 / 10);
    if (view) (*view)["image"] = name;
  }
  if (changes.sidecar)
    std::ofstream(to / "images/IMG_0001.AAE")
        << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<plist version=\"1.0\"><dict>"
           "<key>adjustmentFormatVersion</key><integer>1</integer></dict></plist>\n";
  if (truth) std::ofstream(to / "ground_truth/cameras.json") << cameras.dump(2) << "\n";
  // The benchmark leaves such a set out of its means (the page counts once).
  std::ofstream(to / "VARIANT") << "made by phone-photos from " << from.string() << "\n";
}

}  // namespace docunfold::testing
