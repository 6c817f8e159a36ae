// The photo reader: the same pixels as cv::imread where both read a file,
// EXIF orientation applied, HEIC read, and damaged or foreign files named.
#include "common/photo.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

namespace fs = std::filesystem;

// Runs a shell command; fails the test (with its text) when it fails.
void Shell(const std::string& command) {
  ASSERT_EQ(std::system((command + " > /dev/null 2>&1").c_str()), 0)
      << command << " failed (scripts/install-deps.sh installs the tools)";
}

// An asymmetric picture: orientation mistakes change it.
cv::Mat Asymmetric() {
  cv::Mat m(96, 160, CV_8UC3, cv::Scalar(240, 240, 240));
  cv::rectangle(m, cv::Rect(8, 8, 40, 20), cv::Scalar(0, 0, 255), cv::FILLED);
  cv::circle(m, cv::Point(130, 70), 12, cv::Scalar(255, 0, 0), cv::FILLED);
  cv::putText(m, "Fg", cv::Point(60, 60), cv::FONT_HERSHEY_SIMPLEX, 1.0, cv::Scalar(0, 0, 0), 2);
  return m;
}

void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(ReadPhoto, JpegPixelsAreExactlyOpenCvs) {
  for (const fs::path& path :
       {SampleDir("set01") / "images/view_00.jpg", SampleDir("set07") / "images/view_03.jpg"}) {
    if (!fs::exists(path)) GTEST_SKIP() << "no sample " << path;
    const Photo color = ReadPhoto(path);
    EXPECT_EQ(color.format, PhotoFormat::kJpeg);
    EXPECT_EQ(cv::norm(color.image, cv::imread(path.string(), cv::IMREAD_COLOR), cv::NORM_INF), 0);
    const Photo gray = ReadPhoto(path, PhotoColor::kGray);
    EXPECT_EQ(cv::norm(gray.image, cv::imread(path.string(), cv::IMREAD_GRAYSCALE), cv::NORM_INF),
              0);
  }
}

TEST(ReadPhoto, AppliesEveryExifOrientationAsOpenCvDoes) {
  TempDir tmp;
  cv::imwrite((tmp / "plain.jpg").string(), Asymmetric());
  for (int orientation = 1; orientation <= 8; ++orientation) {
    const fs::path tagged = tmp / ("o" + std::to_string(orientation) + ".jpg");
    Shell("exiftool -n -Orientation=" + std::to_string(orientation) +
          " -Make=Acme -Model='Acme Phone 3'" + " -FocalLengthIn35mmFormat=26 -o " +
          tagged.string() + " " + (tmp / "plain.jpg").string());
    const Photo photo = ReadPhoto(tagged);
    EXPECT_EQ(photo.metadata.exif_orientation, orientation);
    EXPECT_EQ(photo.metadata.camera, "Acme Phone 3");
    EXPECT_EQ(photo.metadata.focal_35mm, 26);
    const cv::Mat expected = cv::imread(tagged.string(), cv::IMREAD_COLOR);
    ASSERT_EQ(photo.image.size(), expected.size()) << "orientation " << orientation;
    EXPECT_EQ(cv::norm(photo.image, expected, cv::NORM_INF), 0) << "orientation " << orientation;
  }
  EXPECT_EQ(ReadPhoto(tmp / "o6.jpg").image.rows, 160);  // turned to portrait
}

TEST(ReadPhoto, ReadsHeicUpright) {
  TempDir tmp;
  const cv::Mat picture = Asymmetric();
  cv::imwrite((tmp / "p.png").string(), picture);
  Shell("heif-enc -q 95 " + (tmp / "p.png").string() + " -o " + (tmp / "p.heic").string());
  const Photo photo = ReadPhoto(tmp / "p.heic");
  EXPECT_EQ(photo.format, PhotoFormat::kHeif);
  ASSERT_EQ(photo.image.size(), picture.size());
  cv::Mat diff;
  cv::absdiff(photo.image, picture, diff);
  EXPECT_LT(cv::mean(diff)[0], 6) << "lossy, but the same picture the same way up";
  EXPECT_EQ(ReadPhoto(tmp / "p.heic", PhotoColor::kGray).image.type(), CV_8UC1);
}

TEST(ReadPhoto, NamesDamagedAndForeignFiles) {
  TempDir tmp;
  std::vector<uchar> jpeg, png;
  cv::imencode(".jpg", Asymmetric(), jpeg);
  cv::imencode(".png", Asymmetric(), png);
  WriteBytes(tmp / "cut.jpg", std::string(jpeg.begin(), jpeg.begin() + long(jpeg.size() * 6 / 10)));
  WriteBytes(tmp / "cut.png", std::string(png.begin(), png.begin() + long(png.size() / 2)));
  WriteBytes(tmp / "text.jpg", "hello, I am a text file");
  WriteBytes(tmp / "empty.jpg", "");
  WriteBytes(tmp / "IMG_0001.AAE", "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<plist/>");
  const auto reason = [&](const std::string& name) -> std::string {
    try {
      ReadPhoto(tmp / name);
    } catch (const PhotoError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      return e.reason();
    }
    return "read";
  };
  EXPECT_EQ(reason("cut.jpg"), "damaged: the file ends early");
  EXPECT_EQ(reason("cut.png").rfind("damaged: ", 0), 0u) << reason("cut.png");
  EXPECT_EQ(reason("text.jpg"), "not a photo");
  EXPECT_EQ(reason("empty.jpg"), "not a photo");
  EXPECT_EQ(reason("IMG_0001.AAE"), "not a photo");
  EXPECT_THROW(ReadPhoto(tmp / "missing.jpg"), InputError);
  // A whole file decodes from memory as from disk.
  const std::string bytes = ReadBytes(tmp / "cut.jpg");
  EXPECT_THROW(DecodePhoto(bytes, "cut.jpg"), PhotoError);
}

// A header may claim any size: more pixels than the file's bytes can hold is
// refused before they are allocated.
TEST(ReadPhoto, RefusesAHeaderClaimingMorePixelsThanItsBytesHold) {
  std::vector<uchar> jpeg;
  cv::imencode(".jpg", Asymmetric(), jpeg);
  std::string bytes(jpeg.begin(), jpeg.end());
  const size_t sof = bytes.find("\xFF\xC0");
  ASSERT_NE(sof, std::string::npos);
  for (size_t i : {sof + 5, sof + 7}) bytes[i] = char(0xEA), bytes[i + 1] = char(0x60);  // 60000
  try {
    DecodePhoto(bytes, "huge.jpg");
    FAIL() << "decoded";
  } catch (const PhotoError& e) {
    EXPECT_NE(std::string(e.what()).find("claims 60000x60000 pixels"), std::string::npos)
        << e.what();
  }
}

// Found by the photo fuzzer: a HEIF whose image has no bit depth made libheif
// start thread after thread until memory ran out.
TEST(ReadPhoto, RefusesHeifWithoutBitDepthAtOnce) {
  try {
    ReadPhoto(SourceDir() / "tests/data/photos/grid-without-bit-depth.heic");
    FAIL() << "decoded";
  } catch (const PhotoError& e) {
    EXPECT_TRUE(e.damaged()) << e.what();
  }
}

// Found by the photo fuzzer: a 562-byte HEIF whose 48x32 image is a grid
// with a 12288x8192 canvas; libheif allocated the canvas (300 MB) before its
// one tile failed to decode. The canvas may not be larger than the image.
TEST(ReadPhoto, RefusesHeifGridLargerThanItsImageBeforeAllocatingIt) {
  try {
    ReadPhoto(SourceDir() / "tests/data/photos/grid-larger-than-its-image.heic");
    FAIL() << "decoded";
  } catch (const PhotoError& e) {
    EXPECT_TRUE(e.damaged()) << e.what();
    EXPECT_NE(std::string(e.what()).find("12288x"), std::string::npos) << e.what();
  }
}

TEST(FocalPixelsFrom35mm, UsesTheDiagonal) {
  // A 4:3 photo 4032 px wide at 26 mm equivalent (a common phone main camera).
  EXPECT_NEAR(FocalPixelsFrom35mm(26, 4032, 3024), 26 * 5040 / 43.2666, 0.5);
}

}  // namespace
}  // namespace docunfold::testing
