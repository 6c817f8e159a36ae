// The photos as sfm hands them to COLMAP (photo_set.h): what is left out,
// how photos are grouped into cameras, and COLMAP's cameras taken back to
// each photo's own pixels.
#include "stages/sfm/photo_set.h"

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/camera.h"
#include "common/errors.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

namespace fs = std::filesystem;

cv::Mat Noise(int rows, int cols) {
  cv::Mat m(rows, cols, CV_8UC3);
  cv::randu(m, 0, 255);
  return m;
}

TEST(PreparePhotos, LeavesOutWhatIsNotAPhotoOrDamagedAndGroupsBySize) {
  TempDir tmp;
  fs::create_directories(tmp / "set/images");
  fs::create_directories(tmp / "copies");
  cv::imwrite((tmp / "set/images/a b.jpg").string(), Noise(60, 80));
  cv::imwrite((tmp / "set/images/b.png").string(), Noise(60, 80));
  cv::imwrite((tmp / "set/images/b.jpg").string(), Noise(80, 60));    // portrait: turned
  cv::imwrite((tmp / "set/images/d.png").string(), Noise(300, 400));  // larger: scaled
  std::ofstream(tmp / "set/images/IMG_0001.AAE") << "<?xml version=\"1.0\"?><plist/>";
  std::ofstream(tmp / "set/images/.DS_Store") << "hidden";
  fs::create_directories(tmp / "set/images/letter 2");  // a folder of photos: never read
  cv::imwrite((tmp / "set/images/letter 2/f.jpg").string(), Noise(60, 80));
  fs::create_directories(tmp / "set/images/.thumbnails");  // hidden: passed over
  {
    std::vector<uchar> jpeg;
    cv::imencode(".jpg", Noise(60, 80), jpeg);
    std::ofstream(tmp / "set/images/e.jpg", std::ios::binary)
        .write(reinterpret_cast<const char*>(jpeg.data()), std::streamsize(jpeg.size() / 2));
  }
  std::vector<cv::Mat> thumbnails;
  const sfm::PhotoSet set = sfm::PreparePhotos(tmp / "set", 200, tmp / "copies", &thumbnails);
  ASSERT_EQ(set.photos.size(), 4u);
  ASSERT_EQ(thumbnails.size(), 4u);
  EXPECT_EQ(thumbnails[3].cols, 200);  // in the photos' order: d.png's copy is the larger
  EXPECT_EQ(thumbnails[0].cols, 80);
  ASSERT_EQ(set.left_out.size(), 3u);
  EXPECT_EQ(set.left_out[0].name, "letter 2/");
  EXPECT_EQ(set.left_out[0].reason, "a folder: its photos are not read");
  EXPECT_EQ(set.left_out[1].name, "IMG_0001.AAE");
  EXPECT_EQ(set.left_out[1].reason, "not a photo");
  EXPECT_EQ(set.left_out[2].name, "e.jpg");
  EXPECT_EQ(set.left_out[2].reason, "damaged: the file ends early");
  EXPECT_EQ(set.LeftOutSummary(), "2 files and 1 folder left out");

  const sfm::PhotoCopy& a = *set.Find("a b.jpg");
  EXPECT_EQ(a.colmap_name, "a_b.jpg");  // COLMAP reads it as it is, through a link
  EXPECT_TRUE(fs::is_symlink(tmp / "copies" / a.colmap_name));
  const sfm::PhotoCopy& c = *set.Find("b.jpg");
  EXPECT_TRUE(c.turned);
  EXPECT_EQ(c.width, 60);
  EXPECT_EQ(c.copy_width, 80);
  EXPECT_EQ(c.colmap_name, "b.png");  // a PNG copy
  EXPECT_EQ(cv::imread((tmp / "copies" / c.colmap_name).string()).cols, 80);
  EXPECT_EQ(set.Find("b.png")->colmap_name, "b-2.png");
  const sfm::PhotoCopy& d = *set.Find("d.png");
  EXPECT_EQ(d.copy_width, 200);
  EXPECT_EQ(d.copy_height, 150);
  // a, b and the turned c share a camera; d's copy has another size.
  EXPECT_EQ(set.groups.size(), 2u);
  EXPECT_EQ(a.group, c.group);
  EXPECT_NE(a.group, d.group);

  // What PreparePhotos throws with too few photos left ("" if it does not).
  auto error = [&] {
    try {
      sfm::PreparePhotos(tmp / "set", 200, "", nullptr);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  fs::remove(tmp / "set/images/b.png");
  fs::remove(tmp / "set/images/b.jpg");
  fs::remove(tmp / "set/images/d.png");
  EXPECT_NE(error().find("1 photo (2 files and 1 folder left out)"), std::string::npos) << error();
  // Every photo in folders: the error counts them (each is logged by name).
  fs::remove(tmp / "set/images/a b.jpg");
  fs::remove(tmp / "set/images/e.jpg");
  fs::remove(tmp / "set/images/IMG_0001.AAE");
  fs::create_directories(tmp / "set/images/letter 3");
  EXPECT_NE(error().find("0 photos (2 folders left out); sfm needs at least 2 views of the page "
                         "(a run reads no folder in it: give it one of them)"),
            std::string::npos)
      << error();
  EXPECT_THROW(sfm::PreparePhotos(tmp / "nope", 200, "", nullptr), InputError);
}

// The same shot saved twice (a file copied, or kept as HEIC and as JPEG) is
// one view: the second file is left out, naming the first. A view taken a
// few centimetres aside is not the same photo.
TEST(PreparePhotos, ASecondFileOfTheSamePhotoIsLeftOut) {
  TempDir tmp;
  fs::create_directories(tmp / "set/images");
  cv::Mat page(600, 800, CV_8UC3, cv::Scalar(60, 90, 120));
  cv::rectangle(page, {150, 100, 500, 400}, cv::Scalar(235, 235, 230), cv::FILLED);
  for (int y = 140; y < 460; y += 24) cv::line(page, {190, y}, {610, y}, cv::Scalar(30, 30, 30), 3);
  cv::GaussianBlur(page, page, {5, 5}, 0);
  cv::imwrite((tmp / "set/images/IMG_0001.png").string(), page);
  cv::imwrite((tmp / "set/images/IMG_0001.jpg").string(), page, {cv::IMWRITE_JPEG_QUALITY, 80});
  fs::copy_file(tmp / "set/images/IMG_0001.png", tmp / "set/images/IMG_0001 (1).png");
  cv::Mat aside;
  cv::warpAffine(page, aside, cv::Mat(cv::Matx23d(1, 0, 40, 0, 1, 25)), page.size(),
                 cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  cv::imwrite((tmp / "set/images/IMG_0002.jpg").string(), aside);

  const sfm::PhotoSet set = sfm::PreparePhotos(tmp / "set", 400, "", nullptr);
  // The original is kept (the shorter name; of equal ones the first).
  EXPECT_EQ(set.Names(), (std::vector<std::string>{"IMG_0001.jpg", "IMG_0002.jpg"}));
  ASSERT_EQ(set.left_out.size(), 2u);
  EXPECT_EQ(set.left_out[0].name, "IMG_0001 (1).png");
  EXPECT_EQ(set.left_out[0].reason, "the same photo as IMG_0001.jpg");
  EXPECT_EQ(set.left_out[1].name, "IMG_0001.png");
  EXPECT_EQ(set.left_out[1].reason, "the same photo as IMG_0001.jpg");
  EXPECT_EQ(set.dir, fs::canonical(tmp / "set/images"));
}

// A point COLMAP sees at pixel c of a turned and scaled copy is where the
// photo shows it, through ToPhotoFrame's camera.
TEST(ToPhotoFrame, TurnedAndScaledCopiesProjectWhereThePhotoShowsThePoint) {
  for (const bool turned : {false, true}) {
    sfm::PhotoCopy copy;
    copy.turned = turned;
    copy.width = turned ? 1203 : 1601;  // odd sizes: x and y scale differ a little
    copy.height = turned ? 1601 : 1203;
    copy.copy_width = 800;
    copy.copy_height = 601;
    sfm::ColmapCamera camera;
    camera.model_id = 2;
    camera.width = 800;
    camera.height = 601;
    camera.params = {700, 401.3, 299.1, 0.04};
    const sfm::PhotoFrame frame = sfm::ToPhotoFrame(camera, copy);
    const double sx = 800.0 / (turned ? copy.height : copy.width);
    const double sy = 601.0 / (turned ? copy.width : copy.height);
    PinholeCamera photo_camera;
    photo_camera.K = frame.K;
    photo_camera.width = copy.width;
    photo_camera.height = copy.height;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.4, 0.4);
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector3d x(u(rng), u(rng), 1 + u(rng));
      const Eigen::Vector2d c = camera.Project(x) + Eigen::Vector2d(0.5, 0.5);  // edges at 0
      const Eigen::Vector2d landscape(c.x() / sx, c.y() / sy);
      const Eigen::Vector2d expected =
          (turned ? Eigen::Vector2d(landscape.y(), copy.height - landscape.x()) : landscape) -
          Eigen::Vector2d(0.5, 0.5);
      const auto got = ProjectDistorted(photo_camera, camera.OpenCvDistortion(), frame.Q * x);
      ASSERT_TRUE(got.has_value());
      EXPECT_LT((*got - expected).norm(), 1e-9) << "turned " << turned;
    }
    EXPECT_NEAR(frame.Q.determinant(), 1, 1e-12);
  }
}

}  // namespace
}  // namespace docunfold::testing
