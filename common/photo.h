// Photos as phones and people hand them over, read the same way by every
// stage (and by sfm for the copies it hands COLMAP):
//  - JPEG through libjpeg, so that a damaged file (an interrupted copy) is
//    told from a whole one, with the EXIF orientation applied;
//  - HEIC/HEIF and AVIF through libheif, which applies the file's own
//    rotation and mirroring;
//  - PNG, TIFF, WebP and BMP through OpenCV.
// The format is told by the file's first bytes, not by its name.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <string_view>

#include "common/errors.h"

namespace docunfold {

namespace fs = std::filesystem;

enum class PhotoFormat { kUnknown, kJpeg, kPng, kTiff, kWebp, kBmp, kHeif };

// The format `head` (a file's first bytes; 12 are enough) announces.
PhotoFormat SniffPhotoFormat(std::string_view head);

// "JPEG", "HEIF", ...; "unknown" for kUnknown.
const char* PhotoFormatName(PhotoFormat format);

// What a photo's EXIF block says, where docunfold uses it.
struct PhotoMetadata {
  int exif_orientation = 1;  // EXIF Orientation as stored (1..8); 1 when absent
  std::string camera;        // EXIF Make and Model ("Apple iPhone 13"); "" when absent
  double focal_35mm = 0;     // EXIF FocalLengthIn35mmFilm (mm); 0 when absent
};

struct Photo {
  cv::Mat image;  // 8-bit BGR (CV_8UC3), or CV_8UC1 when read as gray; upright
  PhotoFormat format = PhotoFormat::kUnknown;
  PhotoMetadata metadata;
};

enum class PhotoColor { kBgr, kGray };

// A file that is not a photo docunfold reads, or one that is but cannot be
// decoded whole. what() names the file; reason() is the short reason a list
// of left-out files gives ("not a photo", "damaged: the file ends early").
class PhotoError : public InputError {
 public:
  PhotoError(const std::string& name, bool damaged, const std::string& detail);
  bool damaged() const { return damaged_; }
  const std::string& reason() const { return reason_; }

 private:
  bool damaged_;
  std::string reason_;
};

// Decodes a photo from memory; `name` is for messages. Throws PhotoError.
// Pixels are those cv::imread gives for the same file (JPEG: the same
// libjpeg with the same settings), turned upright.
Photo DecodePhoto(std::string_view bytes, const std::string& name,
                  PhotoColor color = PhotoColor::kBgr);

// Reads and decodes the photo at `path`: InputError when it is missing,
// PhotoError when it is not a photo or is damaged.
Photo ReadPhoto(const fs::path& path, PhotoColor color = PhotoColor::kBgr);

// The focal length in pixels of a `width` x `height` photo whose 35 mm
// equivalent focal length is `focal_35mm` (defined on the diagonal, as
// CIPA's DC-008 does: a 36 x 24 mm frame's diagonal is 43.27 mm).
double FocalPixelsFrom35mm(double focal_35mm, int width, int height);

}  // namespace docunfold
