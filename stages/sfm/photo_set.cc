#include "stages/sfm/photo_set.h"

#include <algorithm>
#include <map>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <tuple>

#include "common/atomic_file.h"
#include "common/dataset.h"
#include "common/errors.h"
#include "common/program.h"

namespace docunfold::sfm {

namespace {

// The copy's name: the photo's stem in plain ASCII without spaces (COLMAP's
// match lists split at spaces) and `extension`, made unique among `taken`.
std::string CopyName(const std::string& name, const std::string& extension,
                     std::set<std::string>* taken) {
  std::string stem = fs::path(name).stem().string();
  for (char& c : stem)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  if (stem.empty()) stem = "photo";
  std::string candidate = stem + extension;
  for (int k = 2; taken->count(candidate); ++k)
    candidate = stem + "-" + std::to_string(k) + extension;
  taken->insert(candidate);
  return candidate;
}

// True when COLMAP may read the photo file itself: a format its reader
// (FreeImage) decodes as we do, stored upright, landscape and small enough.
// Its pixels are then exactly those COLMAP always saw.
bool ColmapReadsAsIs(const Photo& photo, const PhotoCopy& copy) {
  const bool readable = photo.format == PhotoFormat::kJpeg || photo.format == PhotoFormat::kPng ||
                        photo.format == PhotoFormat::kTiff;
  return readable && photo.metadata.exif_orientation == 1 && !copy.turned &&
         copy.copy_width == copy.width;
}

// Makes the copy of `photo` (upright) for COLMAP; fills the copy's fields.
cv::Mat MakeCopy(const cv::Mat& photo, int max_image_size, PhotoCopy* copy) {
  copy->width = photo.cols;
  copy->height = photo.rows;
  copy->turned = photo.rows > photo.cols;
  cv::Mat landscape;
  if (copy->turned)
    cv::rotate(photo, landscape, cv::ROTATE_90_CLOCKWISE);
  else
    landscape = photo;
  const double scale = std::min(1.0, double(max_image_size) / landscape.cols);
  if (scale >= 1) {
    copy->copy_width = landscape.cols;
    copy->copy_height = landscape.rows;
    return landscape;
  }
  copy->copy_width = std::max(1, int(std::lround(landscape.cols * scale)));
  copy->copy_height = std::max(1, int(std::lround(landscape.rows * scale)));
  cv::Mat small;
  cv::resize(landscape, small, cv::Size(copy->copy_width, copy->copy_height), 0, 0, cv::INTER_AREA);
  return small;
}

// COLMAP's copy of the photo at `path`: a link to the file when COLMAP may
// read it as it is, else `image` as PNG.
void WriteCopy(const fs::path& path, const cv::Mat& image, bool as_is, const fs::path& copy) {
  if (!as_is) return WriteImageAtomic(copy, image, {cv::IMWRITE_PNG_COMPRESSION, 1});
  std::error_code ec;
  fs::create_symlink(fs::absolute(path), copy, ec);
  if (ec)
    throw OutputError(copy.string() + ": cannot link to " + path.string() + ": " + ec.message());
}

// A photo's likeness at 64 pixels across: its copy in grey, turned landscape.
// Two files whose likenesses differ by less than one grey level on average
// hold the same photo (the same shot saved twice, or as HEIC and as JPEG: a
// re-encoding moves it by 0.2, the nearest two views of any bench set by 5.9).
struct Likeness {
  std::string name;
  cv::Mat grey;  // CV_32F
};

Likeness LikenessOf(const std::string& name, const cv::Mat& copy) {
  cv::Mat grey, small;
  if (copy.channels() == 1)
    grey = copy;
  else
    cv::cvtColor(copy, grey, cv::COLOR_BGR2GRAY);
  const int rows = std::max(1, int(std::lround(64.0 * grey.rows / grey.cols)));
  cv::resize(grey, small, cv::Size(64, rows), 0, 0, cv::INTER_AREA);
  Likeness l{name, {}};
  small.convertTo(l.grey, CV_32F);
  return l;
}

// The earlier photo that `l` is the same photo as; nullptr when none.
const Likeness* SamePhotoAs(const Likeness& l, const std::vector<Likeness>& earlier) {
  for (const Likeness& e : earlier)
    if (e.grey.size() == l.grey.size() && cv::norm(e.grey, l.grey, cv::NORM_L1) < l.grey.total())
      return &e;
  return nullptr;
}

// Puts the photos in name order, with their thumbnails (one per photo, in the
// order read), and what was left out, folders first.
void SortByName(PhotoSet* set, std::vector<cv::Mat>* thumbnails) {
  std::vector<size_t> index(set->photos.size());
  std::iota(index.begin(), index.end(), size_t(0));
  std::sort(index.begin(), index.end(),
            [&](size_t a, size_t b) { return set->photos[a].name < set->photos[b].name; });
  std::vector<PhotoCopy> photos;
  std::vector<cv::Mat> small;
  for (size_t i : index) {
    photos.push_back(std::move(set->photos[i]));
    small.push_back((*thumbnails)[i]);
  }
  set->photos = std::move(photos);
  *thumbnails = std::move(small);
  std::stable_sort(
      set->left_out.begin(), set->left_out.end(), [](const LeftOut& a, const LeftOut& b) {
        return std::make_pair(!a.IsFolder(), a.name) < std::make_pair(!b.IsFolder(), b.name);
      });
}

// One camera per (copy size, EXIF camera, EXIF focal length).
void GroupCameras(PhotoSet* set) {
  std::map<std::tuple<int, int, std::string, double>, int> index;
  for (PhotoCopy& p : set->photos) {
    const auto key =
        std::make_tuple(p.copy_width, p.copy_height, p.metadata.camera, p.metadata.focal_35mm);
    auto [it, added] = index.emplace(key, int(set->groups.size()));
    if (added) {
      CameraGroup g;
      g.copy_width = p.copy_width;
      g.copy_height = p.copy_height;
      g.camera = p.metadata.camera;
      g.focal_35mm = p.metadata.focal_35mm;
      if (g.focal_35mm > 0)
        g.focal_prior = FocalPixelsFrom35mm(g.focal_35mm, g.copy_width, g.copy_height);
      set->groups.push_back(g);
    }
    p.group = it->second;
  }
}

}  // namespace

const PhotoCopy* PhotoSet::Find(const std::string& name) const {
  for (const PhotoCopy& p : photos)
    if (p.name == name) return &p;
  return nullptr;
}

std::vector<std::string> PhotoSet::Names() const {
  std::vector<std::string> names;
  for (const PhotoCopy& p : photos) names.push_back(p.name);
  return names;
}

std::string PhotoSet::LeftOutSummary() const {
  const auto folders = size_t(std::count_if(left_out.begin(), left_out.end(),
                                            [](const LeftOut& l) { return l.IsFolder(); }));
  const size_t files = left_out.size() - folders;
  auto count = [](size_t n, const std::string& what) {
    return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
  };
  if (left_out.empty()) return "";
  return (files ? count(files, "file") : "") + (files && folders ? " and " : "") +
         (folders ? count(folders, "folder") : "") + " left out";
}

PhotoSet PreparePhotos(const fs::path& data_dir, int max_image_size, const fs::path& copy_dir,
                       std::vector<cv::Mat>* thumbnails) {
  const DataSet data = OpenDataSet(data_dir);
  PhotoSet set;
  set.dir = data.photos_dir;
  // A folder of photos inside images/ (one per document, or as a phone
  // exported them) would otherwise be passed over without a word.
  for (const fs::path& folder : data.folders) {
    set.left_out.push_back({folder.filename().string() + "/", "a folder: its photos are not read"});
    Log("left out: " + set.left_out.back().name + " (" + set.left_out.back().reason + ")");
  }
  std::set<std::string> taken;
  std::vector<Likeness> likenesses;
  std::vector<cv::Mat> small_copies;  // one per photo kept, in the order read
  Progress progress("reading photos", long(data.images.size()));
  // Read by (length of the name's stem, name): of two files of one photo the
  // original is kept, not the copy a phone or a file manager named
  // "IMG_0001 (1)". The lists are put back in name order below.
  std::vector<fs::path> order = data.images;
  std::stable_sort(order.begin(), order.end(), [](const fs::path& a, const fs::path& b) {
    return a.stem().string().size() < b.stem().string().size();
  });
  for (size_t i = 0; i < order.size(); ++i) {
    const fs::path& path = order[i];
    const std::string name = path.filename().string();
    Photo photo;
    try {
      photo = ReadPhoto(path);
    } catch (const PhotoError& e) {
      set.left_out.push_back({name, e.reason()});
      Log("left out: " + name + " (" + e.reason() + ")");
      progress.Update(long(i + 1));
      continue;
    }
    PhotoCopy copy;
    copy.name = name;
    copy.metadata = photo.metadata;
    const cv::Mat image = MakeCopy(photo.image, max_image_size, &copy);
    const bool as_is = ColmapReadsAsIs(photo, copy);
    photo.image.release();
    // (two copies of one view would give COLMAP a pair with no baseline)
    Likeness likeness = LikenessOf(name, image);
    if (const Likeness* same = SamePhotoAs(likeness, likenesses)) {
      set.left_out.push_back({name, "the same photo as " + same->name});
      Log("left out: " + name + " (" + set.left_out.back().reason + ")");
      progress.Update(long(i + 1));
      continue;
    }
    likenesses.push_back(std::move(likeness));
    copy.colmap_name = CopyName(name, as_is ? path.extension().string() : ".png", &taken);
    if (!copy_dir.empty()) WriteCopy(path, image, as_is, copy_dir / copy.colmap_name);
    if (thumbnails) {
      const double f = std::min(1.0, 640.0 / std::max(image.cols, image.rows));
      cv::Mat small;
      cv::resize(image, small, cv::Size(), f, f, cv::INTER_AREA);
      small_copies.push_back(small);
    } else {
      small_copies.emplace_back();
    }
    set.photos.push_back(std::move(copy));
    progress.Update(long(i + 1));
  }
  SortByName(&set, &small_copies);
  if (thumbnails) thumbnails->insert(thumbnails->end(), small_copies.begin(), small_copies.end());
  if (set.photos.size() < 2) {
    // (a box of documents, a folder of photos each, with a note beside them)
    const bool in_folders = set.photos.empty() && !data.folders.empty();
    throw InputError(set.dir.string() + ": " + std::to_string(set.photos.size()) + " photo" +
                     (set.photos.size() == 1 ? "" : "s") +
                     (set.left_out.empty() ? std::string() : " (" + set.LeftOutSummary() + ")") +
                     "; sfm needs at least 2 views of the page" +
                     (in_folders ? " (a run reads no folder in it: give it one of them)" : ""));
  }
  GroupCameras(&set);
  return set;
}

PhotoFrame ToPhotoFrame(const ColmapCamera& camera, const PhotoCopy& copy) {
  PhotoFrame frame;
  frame.Q.setIdentity();
  const bool scaled = copy.copy_width != (copy.turned ? copy.height : copy.width);
  if (!copy.turned && !scaled) {
    frame.K = camera.PinholeK();
    return frame;
  }
  // In COLMAP's pixel convention (pixel centres at +0.5): the copy's pixel
  // c = K_c x_colmap; the photo's pixel u = A c undoes the scale and the
  // turn; A K_c = K_u Q with K_u upper triangular.
  Eigen::Matrix3d K_c = camera.PinholeK();
  K_c(0, 2) += 0.5;
  K_c(1, 2) += 0.5;
  const double landscape_w = copy.turned ? copy.height : copy.width;
  const double landscape_h = copy.turned ? copy.width : copy.height;
  const double sx = copy.copy_width / landscape_w, sy = copy.copy_height / landscape_h;
  Eigen::Matrix3d A;
  if (copy.turned) {
    // The copy is the photo turned clockwise: copy (x', y') = photo (y', H - x').
    A << 0, 1 / sy, 0, -1 / sx, 0, copy.height, 0, 0, 1;
    frame.Q << 0, 1, 0, -1, 0, 0, 0, 0, 1;
  } else {
    A << 1 / sx, 0, 0, 0, 1 / sy, 0, 0, 0, 1;
  }
  frame.K = A * K_c * frame.Q.transpose();
  frame.K(0, 1) = frame.K(1, 0) = frame.K(2, 0) = frame.K(2, 1) = 0;  // exact zeros
  frame.K(0, 2) -= 0.5;
  frame.K(1, 2) -= 0.5;
  return frame;
}

void NameByPhotos(const PhotoSet& photos, ColmapModel* model) {
  std::map<std::string, std::string> by_copy;
  for (const PhotoCopy& p : photos.photos) by_copy[p.colmap_name] = p.name;
  for (auto& [id, image] : model->images) {
    const auto it = by_copy.find(image.name);
    if (it != by_copy.end()) image.name = it->second;
  }
}

}  // namespace docunfold::sfm
