#include "common/photo.h"

#include <jpeglib.h>
// jpeglib.h first: jerror.h needs its types.
#include <jerror.h>
#include <libexif/exif-data.h>
#include <libheif/heif.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace docunfold {

namespace {

// Larger photos are taken for damaged files: 200 MP is four times the
// largest phone sensor, and a crafted header must not make us allocate
// gigabytes.
constexpr double kMaxPixels = 200e6;
// Nor more pixels than the file's bytes can hold: an evenly white page
// compresses to about 300 pixels a byte in JPEG, PNG or HEIF; a header that
// claims more than ten times that is damaged or made up.
constexpr double kMaxPixelsPerByte = 4000;

// Why `width` x `height` pixels are implausible for a file of `bytes` bytes;
// "" when they are not.
std::string ClaimedSizeProblem(double width, double height, size_t bytes) {
  const double pixels = width * height;
  if (pixels <= kMaxPixels && pixels <= kMaxPixelsPerByte * double(bytes)) return "";
  return "its header claims " + std::to_string(long(width)) + "x" + std::to_string(long(height)) +
         " pixels in " + std::to_string(bytes) + " bytes";
}

void CheckClaimedSize(double width, double height, size_t bytes, const std::string& name) {
  const std::string problem = ClaimedSizeProblem(width, height, bytes);
  if (!problem.empty()) throw PhotoError(name, true, problem);
}

bool StartsWith(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && s.compare(0, prefix.size(), prefix) == 0;
}

// The big-endian 32-bit number at `p` (PNG's header, HEIF's Exif block).
uint32_t BigEndian32(const unsigned char* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}

std::string Trim(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  size_t start = s.find_first_not_of(' ');
  return start == std::string::npos ? std::string() : s.substr(start);
}

std::string EntryText(ExifContent* ifd, ExifTag tag) {
  ExifEntry* e = ifd ? exif_content_get_entry(ifd, tag) : nullptr;
  if (!e || e->format != EXIF_FORMAT_ASCII || !e->data) return "";
  return Trim(std::string(reinterpret_cast<const char*>(e->data), e->size));
}

// Orientation, camera and 35 mm focal length from an EXIF block that starts
// with "Exif\0\0" (a JPEG's APP1 payload; HEIF's block after its offset).
void ParseExif(const unsigned char* data, size_t size, PhotoMetadata* metadata) {
  ExifData* exif = exif_data_new_from_data(data, unsigned(size));
  if (!exif) return;
  const ExifByteOrder order = exif_data_get_byte_order(exif);
  ExifContent* ifd0 = exif->ifd[EXIF_IFD_0];
  if (ExifEntry* e = ifd0 ? exif_content_get_entry(ifd0, EXIF_TAG_ORIENTATION) : nullptr)
    if (e->format == EXIF_FORMAT_SHORT && e->components >= 1 && e->size >= 2) {
      const int o = exif_get_short(e->data, order);
      if (o >= 1 && o <= 8) metadata->exif_orientation = o;
    }
  if (ExifEntry* e =
          exif_content_get_entry(exif->ifd[EXIF_IFD_EXIF], EXIF_TAG_FOCAL_LENGTH_IN_35MM_FILM))
    if (e->format == EXIF_FORMAT_SHORT && e->components >= 1 && e->size >= 2)
      metadata->focal_35mm = exif_get_short(e->data, order);
  const std::string make = EntryText(ifd0, EXIF_TAG_MAKE), model = EntryText(ifd0, EXIF_TAG_MODEL);
  // Phones often repeat the make in the model ("Apple" + "iPhone 13", but
  // "samsung" + "samsung SM-G991B").
  metadata->camera = StartsWith(model, make) ? model : Trim(make + " " + model);
  exif_data_unref(exif);
}

// Turns `image` upright by EXIF orientation `o`, as cv::imread does.
void ApplyOrientation(int o, cv::Mat* image) {
  switch (o) {
    case 2:
      cv::flip(*image, *image, 1);
      break;
    case 3:
      cv::flip(*image, *image, -1);
      break;
    case 4:
      cv::flip(*image, *image, 0);
      break;
    case 5:
      cv::transpose(*image, *image);
      break;
    case 6:
      cv::transpose(*image, *image), cv::flip(*image, *image, 1);
      break;
    case 7:
      cv::transpose(*image, *image), cv::flip(*image, *image, -1);
      break;
    case 8:
      cv::transpose(*image, *image), cv::flip(*image, *image, 0);
      break;
    default:
      break;
  }
}

// ---- JPEG -----------------------------------------------------------------

struct JpegErrors {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  std::string fatal;   // the error that stopped decoding
  std::string damage;  // the first warning that means lost pixels
};

void OnJpegError(j_common_ptr cinfo) {
  auto* errors = reinterpret_cast<JpegErrors*>(cinfo->err);
  char text[JMSG_LENGTH_MAX];
  cinfo->err->format_message(cinfo, text);
  errors->fatal = text;
  std::longjmp(errors->jump, 1);
}

void OnJpegMessage(j_common_ptr cinfo, int level) {
  if (level >= 0) return;  // trace messages
  auto* errors = reinterpret_cast<JpegErrors*>(cinfo->err);
  const int code = cinfo->err->msg_code;
  // Stray bytes between segments: many cameras write them, no pixel is lost.
  if (code == JWRN_EXTRANEOUS_DATA || !errors->damage.empty()) return;
  if (code == JWRN_JPEG_EOF) {
    errors->damage = "the file ends early";
  } else {
    char text[JMSG_LENGTH_MAX];
    cinfo->err->format_message(cinfo, text);
    errors->damage = text;
  }
}

// Decodes with the settings cv::imread uses (its output colour space, the
// default DCT and upsampling), so that the pixels are the same. Returns
// false for a CMYK JPEG, which OpenCV converts itself.
bool DecodeJpeg(std::string_view bytes, const std::string& name, PhotoColor color, Photo* photo) {
  jpeg_decompress_struct cinfo;
  JpegErrors errors;
  cinfo.err = jpeg_std_error(&errors.manager);
  errors.manager.error_exit = OnJpegError;
  errors.manager.emit_message = OnJpegMessage;
  cv::Mat& image = photo->image;
  bool cmyk = false;
  if (setjmp(errors.jump)) {
    jpeg_destroy_decompress(&cinfo);
    image.release();
    throw PhotoError(name, true, errors.fatal);
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, reinterpret_cast<const unsigned char*>(bytes.data()),
               static_cast<unsigned long>(bytes.size()));
  jpeg_save_markers(&cinfo, JPEG_APP0 + 1, 0xFFFF);
  jpeg_read_header(&cinfo, TRUE);
  for (jpeg_saved_marker_ptr m = cinfo.marker_list; m; m = m->next)
    if (m->marker == JPEG_APP0 + 1 && m->data_length > 6 && !std::memcmp(m->data, "Exif\0\0", 6))
      ParseExif(m->data, m->data_length, &photo->metadata);
  errors.fatal = ClaimedSizeProblem(cinfo.image_width, cinfo.image_height, bytes.size());
  if (!errors.fatal.empty()) std::longjmp(errors.jump, 1);
  if (cinfo.num_components == 4) {
    cmyk = true;
  } else {
    const bool gray = color == PhotoColor::kGray;
    cinfo.out_color_space = gray ? JCS_GRAYSCALE : JCS_EXT_BGR;
    cinfo.out_color_components = gray ? 1 : 3;
    jpeg_start_decompress(&cinfo);
    image.create(int(cinfo.output_height), int(cinfo.output_width), gray ? CV_8UC1 : CV_8UC3);
    while (cinfo.output_scanline < cinfo.output_height) {
      JSAMPROW row = image.ptr<uchar>(int(cinfo.output_scanline));
      jpeg_read_scanlines(&cinfo, &row, 1);
    }
    jpeg_finish_decompress(&cinfo);
  }
  jpeg_destroy_decompress(&cinfo);
  if (!errors.damage.empty()) {
    image.release();
    throw PhotoError(name, true, errors.damage);
  }
  return !cmyk;
}

// ---- HEIF -----------------------------------------------------------------

void CheckHeif(const heif_error& error, const std::string& name) {
  if (error.code != heif_error_Ok)
    throw PhotoError(name, true, error.message ? error.message : "libheif failed");
}

void ReadHeifExif(const heif_image_handle* handle, PhotoMetadata* metadata) {
  heif_item_id id;
  if (heif_image_handle_get_list_of_metadata_block_IDs(handle, "Exif", &id, 1) < 1) return;
  std::vector<unsigned char> block(heif_image_handle_get_metadata_size(handle, id));
  if (block.size() < 4 || heif_image_handle_get_metadata(handle, id, block.data()).code) return;
  // The block starts with the offset of the TIFF header past these 4 bytes;
  // libexif wants "Exif\0\0" right before that header.
  const size_t offset = 4 + size_t(BigEndian32(block.data()));
  if (offset >= block.size()) return;
  std::vector<unsigned char> exif = {'E', 'x', 'i', 'f', 0, 0};
  exif.insert(exif.end(), block.begin() + long(offset), block.end());
  ParseExif(exif.data(), exif.size(), metadata);
}

void DecodeHeif(std::string_view bytes, const std::string& name, PhotoColor color, Photo* photo) {
  const std::unique_ptr<heif_context, void (*)(heif_context*)> context(heif_context_alloc(),
                                                                       heif_context_free);
  // libheif decodes a grid's tiles in threads; a made-up file with a huge or
  // broken grid could start a thread per tile. Two serve an iPhone's 48 tiles.
  heif_context_set_max_decoding_threads(context.get(), 2);
  CheckHeif(heif_context_read_from_memory_without_copy(context.get(), bytes.data(), bytes.size(),
                                                       nullptr),
            name);
  heif_image_handle* raw_handle = nullptr;
  CheckHeif(heif_context_get_primary_image_handle(context.get(), &raw_handle), name);
  std::unique_ptr<heif_image_handle, void (*)(const heif_image_handle*)> handle(
      raw_handle, heif_image_handle_release);
  ReadHeifExif(handle.get(), &photo->metadata);
  const int ispe_width = heif_image_handle_get_ispe_width(handle.get());
  const int ispe_height = heif_image_handle_get_ispe_height(handle.get());
  CheckClaimedSize(ispe_width, ispe_height, bytes.size(), name);
  // A grid's canvas is as large as its own descriptor says, which libheif
  // does not compare with the image's size ('ispe'): a file of a few hundred
  // bytes could make it allocate gigabytes. Its limit (a side may not reach
  // it) is used when the image is decoded.
  heif_context_set_maximum_image_size_limit(context.get(), std::max(ispe_width, ispe_height) + 1);
  // As heif-convert does: an image without a bit depth is not decoded.
  if (heif_image_handle_get_luma_bits_per_pixel(handle.get()) < 0)
    throw PhotoError(name, true, "the image has no defined bit depth");
  heif_image* raw_image = nullptr;
  // libheif applies the file's rotation and mirroring (irot, imir) itself;
  // the EXIF orientation of a HEIF file only repeats them.
  CheckHeif(heif_decode_image(handle.get(), &raw_image, heif_colorspace_RGB,
                              heif_chroma_interleaved_RGB, nullptr),
            name);
  std::unique_ptr<heif_image, void (*)(const heif_image*)> image(raw_image, heif_image_release);
  int stride = 0;
  const uint8_t* pixels =
      heif_image_get_plane_readonly(image.get(), heif_channel_interleaved, &stride);
  const int width = heif_image_get_width(image.get(), heif_channel_interleaved);
  const int height = heif_image_get_height(image.get(), heif_channel_interleaved);
  if (!pixels || width <= 0 || height <= 0) throw PhotoError(name, true, "no pixels decoded");
  const cv::Mat rgb(height, width, CV_8UC3, const_cast<uint8_t*>(pixels), size_t(stride));
  cv::cvtColor(rgb, photo->image,
               color == PhotoColor::kGray ? cv::COLOR_RGB2GRAY : cv::COLOR_RGB2BGR);
}

void DecodeWithOpenCv(std::string_view bytes, const std::string& name, PhotoColor color,
                      Photo* photo) {
  // PNG's size is at a fixed place in its header: checked before OpenCV
  // allocates it. For the other formats OpenCV's own limit, set once (a
  // value the user set wins), caps what a made-up header can claim.
  if (photo->format == PhotoFormat::kPng && bytes.size() >= 24) {
    const auto* header = reinterpret_cast<const unsigned char*>(bytes.data());
    CheckClaimedSize(BigEndian32(header + 16), BigEndian32(header + 20), bytes.size(), name);
  }
  static const bool limited = setenv("CV_IO_MAX_IMAGE_PIXELS", "200000000", 0) == 0;
  (void)limited;
  const cv::Mat buffer(1, int(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
  const int flags = (color == PhotoColor::kGray ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR) |
                    cv::IMREAD_IGNORE_ORIENTATION;
  try {
    photo->image = cv::imdecode(buffer, flags);
  } catch (const cv::Exception& e) {
    throw PhotoError(name, true, e.err);
  }
  if (photo->image.empty())
    throw PhotoError(name, true,
                     std::string("the ") + PhotoFormatName(photo->format) +
                         " decoder failed (is the file cut short?)");
}

}  // namespace

PhotoError::PhotoError(const std::string& name, bool damaged, const std::string& detail)
    : InputError(name + ": " +
                 (damaged ? "damaged photo: " + detail
                          : "not a photo docunfold reads (" + detail +
                                "); it reads JPEG, HEIC/HEIF, "
                                "AVIF, PNG, TIFF, WebP and BMP")),
      damaged_(damaged),
      reason_(damaged ? "damaged: " + detail : "not a photo") {}

PhotoFormat SniffPhotoFormat(std::string_view head) {
  using namespace std::string_view_literals;
  if (StartsWith(head, "\xFF\xD8\xFF"sv)) return PhotoFormat::kJpeg;
  if (StartsWith(head, "\x89PNG\r\n\x1A\n"sv)) return PhotoFormat::kPng;
  if (StartsWith(head, "II*\0"sv) || StartsWith(head, "MM\0*"sv)) return PhotoFormat::kTiff;
  if (head.size() >= 12 && StartsWith(head, "RIFF") && head.substr(8, 4) == "WEBP")
    return PhotoFormat::kWebp;
  if (StartsWith(head, "BM")) return PhotoFormat::kBmp;
  if (head.size() >= 12) {
    const heif_filetype_result kind =
        heif_check_filetype(reinterpret_cast<const uint8_t*>(head.data()), int(head.size()));
    if (kind == heif_filetype_yes_supported) return PhotoFormat::kHeif;
  }
  return PhotoFormat::kUnknown;
}

const char* PhotoFormatName(PhotoFormat format) {
  switch (format) {
    case PhotoFormat::kJpeg:
      return "JPEG";
    case PhotoFormat::kPng:
      return "PNG";
    case PhotoFormat::kTiff:
      return "TIFF";
    case PhotoFormat::kWebp:
      return "WebP";
    case PhotoFormat::kBmp:
      return "BMP";
    case PhotoFormat::kHeif:
      return "HEIF";
    case PhotoFormat::kUnknown:
      break;
  }
  return "unknown";
}

Photo DecodePhoto(std::string_view bytes, const std::string& name, PhotoColor color) {
  Photo photo;
  if (bytes.empty()) throw PhotoError(name, false, "an empty file");
  photo.format = SniffPhotoFormat(bytes.substr(0, 64));
  switch (photo.format) {
    case PhotoFormat::kUnknown:
      throw PhotoError(name, false, "its first bytes are no image format's");
    case PhotoFormat::kHeif:
      DecodeHeif(bytes, name, color, &photo);
      return photo;
    case PhotoFormat::kJpeg:
      if (!DecodeJpeg(bytes, name, color, &photo)) DecodeWithOpenCv(bytes, name, color, &photo);
      ApplyOrientation(photo.metadata.exif_orientation, &photo.image);
      return photo;
    default:
      DecodeWithOpenCv(bytes, name, color, &photo);
      return photo;
  }
}

Photo ReadPhoto(const fs::path& path, PhotoColor color) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path.string() + ": no such file");
  const auto size = fs::file_size(path, ec);
  std::ifstream in(path, std::ios::binary);
  std::string bytes(ec ? 0 : size, '\0');
  if (ec || !in.read(bytes.data(), std::streamsize(bytes.size())))
    throw InputError(path.string() + ": cannot be read");
  return DecodePhoto(bytes, path.string(), color);
}

double FocalPixelsFrom35mm(double focal_35mm, int width, int height) {
  return focal_35mm * std::hypot(double(width), double(height)) / std::hypot(36.0, 24.0);
}

}  // namespace docunfold
