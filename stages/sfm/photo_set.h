// The photos of a data set as sfm hands them to COLMAP. COLMAP reads the
// pixels as stored (it ignores EXIF orientation and cannot read HEIC), so it
// gets copies made by the common photo reader: upright, turned to landscape
// when the photo is portrait (so that photos from one phone held either way
// share one camera), scaled to a long side of at most --max-image-size, as
// PNG named without spaces. Photos share a COLMAP camera when their copies
// have one size and their EXIF names the same camera and focal length.
// ToPhotoFrame takes COLMAP's cameras back to each photo's own pixels.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/photo.h"
#include "stages/sfm/colmap_model.h"

namespace docunfold::sfm {

namespace fs = std::filesystem;

struct PhotoCopy {
  std::string name;           // file in images/
  std::string colmap_name;    // the copy in colmap/images/ (COLMAP's image name)
  int width = 0, height = 0;  // the upright photo, pixels
  bool turned = false;        // the copy is the upright photo turned 90° clockwise
  int copy_width = 0, copy_height = 0;
  int group = 0;  // index into PhotoSet::groups
  PhotoMetadata metadata;
};

// Photos that share one COLMAP camera.
struct CameraGroup {
  int copy_width = 0, copy_height = 0;
  std::string camera;      // EXIF make and model ("" when absent)
  double focal_35mm = 0;   // EXIF 35 mm equivalent focal length (mm); 0 when absent
  double focal_prior = 0;  // COLMAP's focal length prior from it (copy pixels); 0 = none
};

// A file or folder of images/ that is not used, and why ("not a photo",
// "damaged: the file ends early", "a folder: ...").
struct LeftOut {
  std::string name;  // a folder's ends in '/'
  std::string reason;

  bool IsFolder() const { return !name.empty() && name.back() == '/'; }
};

struct PhotoSet {
  fs::path dir;                   // the photos' own folder (links resolved)
  std::vector<PhotoCopy> photos;  // the readable photos, sorted by name
  std::vector<CameraGroup> groups;
  std::vector<LeftOut> left_out;

  const PhotoCopy* Find(const std::string& name) const;  // by file name; nullptr if absent
  std::vector<std::string> Names() const;                // the photos' file names, in order
  // "2 files left out", "1 file and 1 folder left out"; "" when nothing is.
  std::string LeftOutSummary() const;
};

// Reads every file in <data_dir>/images (hidden files aside): each photo is
// turned upright; when `copy_dir` is not empty its copy is written there, and
// when `thumbnails` is given the copy scaled to a long side of at most 640 px
// is appended, in the photos' order. Files that are not photos or are
// damaged, a second file of the same photo, and folders are left out, each
// logged in one line. InputError when the folder is missing or fewer than 2
// photos remain.
PhotoSet PreparePhotos(const fs::path& data_dir, int max_image_size, const fs::path& copy_dir,
                       std::vector<cv::Mat>* thumbnails);

// COLMAP's camera of a copy, seen from the photo: K in the upright photo's
// pixels (our convention, camera.h), and the rotation that takes COLMAP's
// camera frame to the upright photo's (x_photo = Q x_colmap; the identity
// unless the copy was turned). The lens distortion is the same in both
// frames: it is radial, and Q turns about the optical axis.
struct PhotoFrame {
  Eigen::Matrix3d K;
  Eigen::Matrix3d Q;
};
PhotoFrame ToPhotoFrame(const ColmapCamera& camera, const PhotoCopy& copy);

// Renames the model's images from the copies' names to the photos'.
void NameByPhotos(const PhotoSet& photos, ColmapModel* model);

}  // namespace docunfold::sfm
