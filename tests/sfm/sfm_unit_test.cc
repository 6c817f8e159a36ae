// Unit tests of sfm's parts: COLMAP's binary model reader and pixel
// convention, the reference frame, the reference-view score, the image
// checks, undistortion and exact matching. No COLMAP
// needed.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <Eigen/Core>
#include <cstdio>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <tuple>

#include "common/errors.h"
#include "stages/sfm/colmap_model.h"
#include "stages/sfm/descriptor_dots.h"
#include "stages/sfm/matching.h"
#include "stages/sfm/reference_view.h"
#include "stages/sfm/sfm.h"
#include "tests/sfm/sfm_eval.h"
#include "tests/support/look_at.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

using sfm::ColmapCamera;
using sfm::ColmapImage;
using sfm::ColmapModel;
using sfm::ColmapPoint;

// --- a writer of COLMAP's binary format, as COLMAP 3.8 lays it out ---------

class Bytes {
 public:
  template <typename T>
  void Put(T v) {
    const char* p = reinterpret_cast<const char*>(&v);
    data_.append(p, sizeof(T));
  }
  void PutString(const std::string& s) { data_.append(s.c_str(), s.size() + 1); }
  void Save(const fs::path& path, size_t truncate_by = 0) const {
    std::ofstream f(path, std::ios::binary);
    f.write(data_.data(), std::streamsize(data_.size() - truncate_by));
  }

 private:
  std::string data_;
};

struct FakePoint {
  Eigen::Vector3d xyz;
  std::vector<uint32_t> images;
};

// Writes a model with one camera, the given images (id = index + 1) and
// points; each image lists a 2D point per observation.
void WriteModel(const fs::path& dir, const ColmapCamera& camera,
                const std::vector<ColmapImage>& images, const std::vector<FakePoint>& points,
                size_t truncate_points_by = 0) {
  fs::create_directories(dir);
  Bytes c;
  c.Put<uint64_t>(1);
  c.Put<uint32_t>(camera.id);
  c.Put<int32_t>(camera.model_id);
  c.Put<uint64_t>(camera.width);
  c.Put<uint64_t>(camera.height);
  for (double p : camera.params) c.Put<double>(p);
  c.Save(dir / "cameras.bin");
  // Observations: image id -> list of point ids.
  std::map<uint32_t, std::vector<uint64_t>> obs;
  for (size_t i = 0; i < points.size(); ++i)
    for (uint32_t im : points[i].images) obs[im].push_back(i + 1);
  Bytes m;
  m.Put<uint64_t>(images.size());
  for (const ColmapImage& im : images) {
    m.Put<uint32_t>(im.id);
    m.Put<double>(im.q.w());
    m.Put<double>(im.q.x());
    m.Put<double>(im.q.y());
    m.Put<double>(im.q.z());
    for (int k = 0; k < 3; ++k) m.Put<double>(im.t[k]);
    m.Put<uint32_t>(camera.id);
    m.PutString(im.name);
    const auto& mine = obs[im.id];
    m.Put<uint64_t>(mine.size() + 1);  // one keypoint without a 3D point
    for (uint64_t id : mine) {
      m.Put<double>(10.0);
      m.Put<double>(20.0);
      m.Put<int64_t>(int64_t(id));
    }
    m.Put<double>(1.0);
    m.Put<double>(2.0);
    m.Put<int64_t>(-1);
  }
  m.Save(dir / "images.bin");
  Bytes p;
  p.Put<uint64_t>(points.size());
  std::map<uint32_t, uint32_t> next_idx;
  for (size_t i = 0; i < points.size(); ++i) {
    p.Put<uint64_t>(i + 1);
    for (int k = 0; k < 3; ++k) p.Put<double>(points[i].xyz[k]);
    p.Put<uint8_t>(10);
    p.Put<uint8_t>(20);
    p.Put<uint8_t>(uint8_t(i));
    p.Put<double>(0.25 * double(i % 4));
    p.Put<uint64_t>(points[i].images.size());
    for (uint32_t im : points[i].images) {
      p.Put<uint32_t>(im);
      p.Put<uint32_t>(next_idx[im]++);
    }
  }
  p.Save(dir / "points3D.bin", truncate_points_by);
}

ColmapImage MakeImage(uint32_t id, const std::string& name, const Eigen::Matrix3d& R,
                      const Eigen::Vector3d& t) {
  ColmapImage im;
  im.id = id;
  im.camera_id = 1;
  im.name = name;
  im.q = Eigen::Quaterniond(R);
  im.t = t;
  return im;
}

// A camera at `center` looking at `target` (OpenCV axes, y roughly down).
ColmapImage LookAt(uint32_t id, const std::string& name, const Eigen::Vector3d& center,
                   const Eigen::Vector3d& target) {
  const Eigen::Matrix3d R = LookAtRotation(center, target);
  return MakeImage(id, name, R, -R * center);
}

ColmapCamera SimpleRadial(double f, int w, int h, double k) {
  ColmapCamera c;
  c.id = 1;
  c.model_id = 2;
  c.width = w;
  c.height = h;
  c.params = {f, w / 2.0, h / 2.0, k};
  return c;
}

// A page of points on z = 0 (0.2 x 0.3), seen by every image.
std::vector<FakePoint> PagePoints(int n, const std::vector<uint32_t>& images, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<FakePoint> pts;
  for (int i = 0; i < n; ++i) pts.push_back({{0.2 * u(rng), 0.3 * u(rng), 0.0}, images});
  return pts;
}

TEST(ColmapModelTest, ReadsWhatColmapWrites) {
  TempDir tmp;
  const ColmapCamera cam = SimpleRadial(1000, 800, 600, 0.01);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<ColmapImage> images = {
      MakeImage(1, "a.jpg", Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 2)),
      MakeImage(2, "b.jpg", R, Eigen::Vector3d(0.1, 0, 2))};
  WriteModel(tmp.path(), cam, images,
             {{{0, 0, 0}, {1, 2}}, {{0.1, 0, 0}, {1}}, {{0, 0.1, 0.1}, {2, 1}}});
  const ColmapModel m = sfm::ReadColmapModel(tmp.path());
  ASSERT_EQ(m.cameras.size(), 1u);
  ASSERT_EQ(m.images.size(), 2u);
  ASSERT_EQ(m.points.size(), 3u);
  EXPECT_EQ(m.cameras.at(1).model_id, 2);
  EXPECT_EQ(m.cameras.at(1).width, 800);
  EXPECT_EQ(m.images.at(2).name, "b.jpg");
  EXPECT_TRUE(m.images.at(2).R().isApprox(R, 1e-12));
  EXPECT_TRUE(m.images.at(2).Center().isApprox(-R.transpose() * Eigen::Vector3d(0.1, 0, 2)));
  EXPECT_EQ(m.images.at(1).num_points2d, 4u);  // 3 observations + 1 loose keypoint
  EXPECT_EQ(m.images.at(1).num_points3d, 3u);
  EXPECT_EQ(m.points[2].image_ids, (std::vector<uint32_t>{2, 1}));
  EXPECT_EQ(m.points[2].rgb[2], 2);
  EXPECT_EQ(m.NumObservations(), 5u);
  // Mean over observations: errors 0, 0.25, 0.5 with 2, 1, 2 observations.
  EXPECT_NEAR(m.MeanReprojectionError(), (0 * 2 + 0.25 * 1 + 0.5 * 2) / 5.0, 1e-12);
}

TEST(ColmapModelTest, TruncatedFileIsAnErrorNamingIt) {
  TempDir tmp;
  WriteModel(tmp.path(), SimpleRadial(1000, 800, 600, 0),
             {MakeImage(1, "a.jpg", Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero())},
             {{{0, 0, 1}, {1}}}, /*truncate_points_by=*/5);
  try {
    sfm::ReadColmapModel(tmp.path());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("points3D.bin"), std::string::npos) << e.what();
  }
  EXPECT_THROW(sfm::ReadColmapModel(tmp / "missing"), std::runtime_error);
}

TEST(ColmapModelTest, UnknownImageInTrackIsAnError) {
  TempDir tmp;
  WriteModel(tmp.path(), SimpleRadial(1000, 800, 600, 0),
             {MakeImage(1, "a.jpg", Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero())},
             {{{0, 0, 1}, {7}}});
  EXPECT_THROW(sfm::ReadColmapModel(tmp.path()), std::runtime_error);
}

TEST(ColmapModelTest, PixelConventionAndDistortionMatchOpenCv) {
  // COLMAP's principal point 400,300 for an 800x600 image is 399.5,299.5
  // in our convention (pixel centres at integers).
  const ColmapCamera cam = SimpleRadial(900, 800, 600, -0.05);
  const Eigen::Matrix3d K = cam.PinholeK();
  EXPECT_DOUBLE_EQ(K(0, 2), 399.5);
  EXPECT_DOUBLE_EQ(K(1, 2), 299.5);
  EXPECT_TRUE(cam.HasDistortion());
  const auto d = cam.OpenCvDistortion();
  cv::Mat cvK;
  cv::eigen2cv(K, cvK);
  const cv::Mat dist = (cv::Mat_<double>(1, 4) << d[0], d[1], d[2], d[3]);
  std::vector<cv::Point3d> pts = {{0.1, -0.2, 1.0}, {-0.3, 0.25, 1.2}, {0, 0, 2}};
  std::vector<cv::Point2d> projected;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cvK, dist, projected);
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector2d ours = cam.Project({pts[i].x, pts[i].y, pts[i].z});
    EXPECT_NEAR(ours.x(), projected[i].x, 1e-9);
    EXPECT_NEAR(ours.y(), projected[i].y, 1e-9);
  }
  ColmapCamera pinhole;
  pinhole.model_id = 1;
  pinhole.params = {900, 910, 400, 300};
  EXPECT_FALSE(pinhole.HasDistortion());
  EXPECT_DOUBLE_EQ(pinhole.PinholeK()(1, 1), 910);
  EXPECT_DOUBLE_EQ(pinhole.MeanFocal(), 905);
  EXPECT_EQ(sfm::CameraModelId("RADIAL"), 3);
  EXPECT_EQ(sfm::CameraModelId("OPENCV"), -1);
}

TEST(ReferenceFrameTest, ReferenceIsIdentityAtMedianDepthOneAndPixelsAreKept) {
  ColmapModel m;
  m.cameras[1] = SimpleRadial(1000, 800, 600, 0);
  m.images[1] = LookAt(1, "v0.jpg", {0.3, -0.1, 5}, {0, 0, 0});
  m.images[2] = LookAt(2, "v1.jpg", {-0.2, 0.4, 4}, {0.05, 0, 0});
  m.images[3] = LookAt(3, "v2.jpg", {1.5, 0.2, 4.5}, {0, 0.1, 0});
  for (const FakePoint& p : PagePoints(101, {1, 2, 3})) {
    ColmapPoint q;
    q.xyz = p.xyz * 10.0;  // COLMAP's arbitrary scale
    q.image_ids = p.images;
    m.points.push_back(q);
  }
  m.points.push_back({});  // a point only v1 and v2 see, far behind
  m.points.back().xyz = {0, 0, -30};
  m.points.back().image_ids = {2, 3};

  sfm::PhotoSet photos;
  for (const char* name : {"v0.jpg", "v1.jpg", "v2.jpg"}) {
    sfm::PhotoCopy p;
    p.name = p.colmap_name = name;
    p.width = p.copy_width = 800;
    p.height = p.copy_height = 600;
    photos.photos.push_back(p);
  }
  CameraSet cams;
  std::vector<Eigen::Vector3d> pts;
  const double divisor = sfm::ToReferenceFrame(m, photos, "v1.jpg", &cams, &pts);
  EXPECT_GT(divisor, 0);
  ASSERT_EQ(cams.views.size(), 3u);
  EXPECT_EQ(cams.reference, "v1.jpg");
  const PinholeCamera* ref = cams.Find("v1.jpg");
  ASSERT_NE(ref, nullptr);
  EXPECT_TRUE(ref->R.isIdentity(0));
  EXPECT_TRUE(ref->t.isZero(0));
  // Median depth of the points v1 sees is 1.
  std::vector<double> depths;
  for (size_t i = 0; i < pts.size(); ++i)
    if (std::count(m.points[i].image_ids.begin(), m.points[i].image_ids.end(), 2u))
      depths.push_back(pts[i].z());
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  EXPECT_NEAR(depths[depths.size() / 2], 1.0, 1e-12);
  // Every point lands on the same pixel in every view as before.
  for (const PinholeCamera& c : cams.views) {
    const ColmapImage* im = nullptr;
    for (const auto& [id, image] : m.images)
      if (image.name == c.image) im = &image;
    ASSERT_NE(im, nullptr);
    EXPECT_TRUE((c.R * c.R.transpose()).isIdentity(1e-12));
    for (size_t i = 0; i < 100; i += 7) {
      const Eigen::Vector2d before = m.cameras[1].Project(im->R() * m.points[i].xyz + im->t);
      const Eigen::Vector2d after = c.Project(pts[i]);
      EXPECT_LT((before - after).norm(), 1e-9) << c.image;
    }
  }
  EXPECT_THROW(sfm::ToReferenceFrame(m, photos, "nope.jpg", &cams, &pts), std::invalid_argument);
}

TEST(ReferenceViewTest, NormalsOfAPlaneAreItsNormal) {
  std::vector<Eigen::Vector3d> pts;
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -1, 0.3).normalized()).toRotationMatrix();
  for (const FakePoint& p : PagePoints(200, {1})) pts.push_back(R * p.xyz);
  const auto normals = sfm::EstimateNormals(pts, 12);
  for (const Eigen::Vector3d& n : normals) EXPECT_GT(std::abs(n.dot(R.col(2))), 0.999);
}

TEST(ReferenceViewTest, PrefersTheFrontalViewThatSeesTheWholePage) {
  ColmapModel m;
  m.cameras[1] = SimpleRadial(1000, 800, 600, 0);
  // Page 0.2 x 0.3 on z = 0; cameras above it (z < 0 is "up" for OpenCV's
  // y-down convention does not matter here: LookAt handles it).
  m.images[1] = LookAt(1, "oblique.jpg", {0.35, 0.0, -0.5}, {0, 0, 0});    // ~35 deg
  m.images[2] = LookAt(2, "frontal.jpg", {0.05, 0.03, -0.6}, {0, 0, 0});   // ~5 deg
  m.images[3] = LookAt(3, "too_close.jpg", {0.0, 0.0, -0.2}, {0, 0, 0});   // head-on, page cut
  m.images[4] = LookAt(4, "slanted.jpg", {-0.3, 0.25, -0.45}, {0, 0, 0});  // ~40 deg
  for (const FakePoint& p : PagePoints(400, {1, 2, 3, 4})) {
    ColmapPoint q;
    q.xyz = p.xyz;
    // Views only observe what they can see in their image.
    for (uint32_t id : p.images) {
      const Eigen::Vector3d xc = m.images[id].R() * q.xyz + m.images[id].t;
      const Eigen::Vector2d px = m.cameras[1].Project(xc);
      if (xc.z() > 0 && px.x() >= 0 && px.y() >= 0 && px.x() < 800 && px.y() < 600)
        q.image_ids.push_back(id);
    }
    m.points.push_back(q);
  }
  const auto scores = sfm::ScoreReferenceViews(m);
  ASSERT_EQ(scores.size(), 4u);
  EXPECT_EQ(scores[0].image, "frontal.jpg");
  for (const auto& s : scores) {
    SCOPED_TRACE(s.image);
    EXPECT_GE(s.frontality, 0);
    EXPECT_LE(s.frontality, 1);
    if (s.image == "too_close.jpg") {
      EXPECT_LT(s.coverage, 0.9);
      EXPECT_GT(s.frontality, 0.95);
    } else {
      EXPECT_DOUBLE_EQ(s.coverage, 1.0);
    }
  }
  auto find = [&](const std::string& name) {
    return *std::find_if(scores.begin(), scores.end(),
                         [&](const sfm::ViewScore& s) { return s.image == name; });
  };
  EXPECT_GT(find("frontal.jpg").frontality, find("oblique.jpg").frontality);
  EXPECT_GT(find("oblique.jpg").frontality, find("slanted.jpg").frontality);
}

TEST(ReferenceViewTest, FrontalitySettlesANearTie) {
  // A view 35 degrees off, closer to the page, resolves its worst-seen tenth
  // a little better than a head-on view further away; the head-on view
  // still wins (set08: a slanted view that alone sees a band of the page
  // has no point there, so its resolution is measured without the band).
  ColmapModel m;
  m.cameras[1] = SimpleRadial(500, 800, 600, 0);
  m.images[1] = LookAt(1, "head_on.jpg", {0.02, 0.01, -0.6}, {0, 0, 0});
  m.images[2] = LookAt(2, "slanted.jpg", {0.189, 0.0, -0.27}, {0, 0, 0});
  for (const FakePoint& p : PagePoints(400, {1, 2})) {
    ColmapPoint q;
    q.xyz = p.xyz;
    q.image_ids = p.images;
    m.points.push_back(q);
  }
  const auto scores = sfm::ScoreReferenceViews(m);
  ASSERT_EQ(scores.size(), 2u);
  const sfm::ViewScore& head_on = scores[0].image == "head_on.jpg" ? scores[0] : scores[1];
  const sfm::ViewScore& slanted = scores[0].image == "head_on.jpg" ? scores[1] : scores[0];
  EXPECT_DOUBLE_EQ(head_on.coverage, 1.0);
  EXPECT_DOUBLE_EQ(slanted.coverage, 1.0);
  EXPECT_GT(slanted.resolution, 1.05 * head_on.resolution);
  EXPECT_LT(slanted.frontality, 0.9);
  EXPECT_EQ(scores[0].image, "head_on.jpg");
}

TEST(ReferenceViewTest, AViewThatSeesPartOfThePageFromBehindLoses) {
  // set02 in one CI run: view_01, a little sharper and more frontal, sees
  // 1.5 % of the page (a curled corner) from behind; view_00 sees it all.
  sfm::ViewScore curled, whole;
  curled.coverage = whole.coverage = 1.0;
  curled.resolution = 51.4, curled.frontality = 0.936, curled.hidden = 0.015;
  whole.resolution = 50.4, whole.frontality = 0.91, whole.hidden = 0.0;
  EXPECT_GT(sfm::ReferenceScore(whole, 51.4), sfm::ReferenceScore(curled, 51.4));
  // The normals' noise (0.1-0.4 % on every view) moves a score by a few percent.
  sfm::ViewScore noisy = whole;
  noisy.hidden = 0.003;
  EXPECT_GT(sfm::ReferenceScore(noisy, 51.4), 0.96 * sfm::ReferenceScore(whole, 51.4));
  // Off, the sharper view wins, as before.
  sfm::ReferenceOptions off;
  off.hidden_penalty = 0;
  EXPECT_GT(sfm::ReferenceScore(curled, 51.4, off), sfm::ReferenceScore(whole, 51.4, off));
}

TEST(UndistortTest, DistortedPixelMovesToThePinholeProjection) {
  // A white dot where the distorted camera sees a 3D point ends up where
  // the pinhole camera (same K) sees it.
  const ColmapCamera cam = SimpleRadial(500, 640, 480, 0.08);
  const Eigen::Vector3d X(0.45, -0.3, 1.0);
  const Eigen::Vector2d distorted = cam.Project(X);
  const Eigen::Vector3d kx = cam.PinholeK() * X;
  const Eigen::Vector2d pinhole = kx.head<2>() / kx.z();
  ASSERT_GT((distorted - pinhole).norm(), 5.0);  // the test means something
  cv::Mat photo(480, 640, CV_8UC3, cv::Scalar(0, 0, 0));
  cv::circle(photo, cv::Point(int(std::lround(distorted.x())), int(std::lround(distorted.y()))), 3,
             cv::Scalar(255, 255, 255), cv::FILLED);
  const cv::Mat out = sfm::UndistortPhoto(photo, cam.PinholeK(), cam.OpenCvDistortion());
  ASSERT_EQ(out.size(), photo.size());
  cv::Mat grey;
  cv::cvtColor(out, grey, cv::COLOR_BGR2GRAY);
  const cv::Moments mo = cv::moments(grey, false);
  const Eigen::Vector2d centroid(mo.m10 / mo.m00, mo.m01 / mo.m00);
  EXPECT_LT((centroid - pinhole).norm(), 0.6)
      << "centroid " << centroid.transpose() << " pinhole " << pinhole.transpose();
  // A pinhole camera leaves the photo as it is.
  ColmapCamera plain = cam;
  plain.params[3] = 0;
  EXPECT_EQ(cv::norm(sfm::UndistortPhoto(photo, plain.PinholeK(), plain.OpenCvDistortion()), photo,
                     cv::NORM_INF),
            0);
}

TEST(UndistortTest, LeavesNoDarkFrameAtTheBorder) {
  // A slight distortion (set08's sfm estimated k = 0.00077) maps the last row
  // and column a fraction of a pixel past the photo: they must stay paper.
  const cv::Mat photo(480, 640, CV_8UC3, cv::Scalar(200, 200, 200));
  for (const double k : {0.0008, -0.0008, 0.05}) {
    const ColmapCamera camera = SimpleRadial(500, 640, 480, k);
    const cv::Mat out = sfm::UndistortPhoto(photo, camera.PinholeK(), camera.OpenCvDistortion());
    double darkest = 0;
    cv::minMaxLoc(out.reshape(1), &darkest);
    EXPECT_GE(darkest, 195) << "k " << k;
  }
}

TEST(SfmEvalTest, PointTriangleDistance) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_DOUBLE_EQ(PointTriangleDistance({0.2, 0.2, 0.5}, a, b, c), 0.5);         // face
  EXPECT_DOUBLE_EQ(PointTriangleDistance({-1, 0, 0}, a, b, c), 1.0);              // vertex a
  EXPECT_DOUBLE_EQ(PointTriangleDistance({0.5, -2, 0}, a, b, c), 2.0);            // edge ab
  EXPECT_NEAR(PointTriangleDistance({1, 1, 0}, a, b, c), std::sqrt(0.5), 1e-12);  // edge bc
  EXPECT_DOUBLE_EQ(PointTriangleDistance({2, 0, 0}, a, b, c), 1.0);               // vertex b
}

// --- exact matching ------------------------------------------------------

// n random SIFT-like descriptors: non-negative, L2 norm 512, as bytes.
Eigen::Matrix<float, Eigen::Dynamic, 128, Eigen::RowMajor> RandomDescriptors(int n,
                                                                             std::mt19937* rng) {
  std::uniform_real_distribution<float> u(0, 1);
  Eigen::Matrix<float, Eigen::Dynamic, 128, Eigen::RowMajor> d(n, 128);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix<float, 1, 128> row;
    for (int k = 0; k < 128; ++k) row[k] = u(*rng) * u(*rng);
    row *= 512 / row.norm();
    for (int k = 0; k < 128; ++k) d(i, k) = std::min(255.f, std::round(row[k]));
  }
  return d;
}

TEST(ExactMatchingTest, FindsTheSameFeaturesAndRejectsAmbiguousOnes) {
  std::mt19937 rng(7);
  sfm::ImageDescriptors a, b;
  a.rows = RandomDescriptors(300, &rng);
  // b: a's rows 0..199 in reverse order, each a little perturbed, then 100
  // unrelated ones; row 0 of a appears twice in b (ambiguous: ratio test).
  b.rows.resize(301, 128);
  std::uniform_int_distribution<int> jitter(-2, 2);
  for (int i = 0; i < 200; ++i)
    for (int k = 0; k < 128; ++k)
      b.rows(199 - i, k) = std::clamp(a.rows(i, k) + float(jitter(rng)), 0.f, 255.f);
  b.rows.middleRows(200, 100) = RandomDescriptors(100, &rng);
  b.rows.row(300) = b.rows.row(199);
  const auto matches = sfm::MatchDescriptors(a, b, sfm::MatchCriteria{});
  // A third image: a's first 100 rows.
  auto c_of = [](const sfm::ImageDescriptors& from) {
    sfm::ImageDescriptors c;
    c.rows = from.rows.topRows(100);
    return c;
  };
  int right = 0;
  for (const auto& [i, j] : matches) {
    EXPECT_LT(i, 200);
    EXPECT_EQ(j, 199 - i);
    right += j == 199 - i;
    EXPECT_NE(i, 0);  // two equally near candidates
  }
  EXPECT_GE(right, 190);
  // The same call gives the same matches; swapping the images swaps them.
  EXPECT_EQ(sfm::MatchDescriptors(a, b, sfm::MatchCriteria{}), matches);
  const auto swapped = sfm::MatchDescriptors(b, a, sfm::MatchCriteria{});
  ASSERT_EQ(swapped.size(), matches.size());
  for (const auto& [j, i] : swapped) EXPECT_EQ(j, 199 - i);
  // Every pair, on two threads: the same as one pair at a time, in order.
  int calls = 0;
  const auto all = sfm::MatchAllPairs({a, b, c_of(a)}, sfm::MatchCriteria{}, 2,
                                      [&](int done) { EXPECT_EQ(done, ++calls); });
  EXPECT_EQ(calls, 3);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0], matches);
  EXPECT_EQ(all[1], sfm::MatchDescriptors(a, c_of(a), sfm::MatchCriteria{}));
  EXPECT_EQ(all[2], sfm::MatchDescriptors(b, c_of(a), sfm::MatchCriteria{}));
  // Unrelated features: the ratio test leaves (almost) nothing.
  sfm::ImageDescriptors c;
  c.rows = RandomDescriptors(300, &rng);
  EXPECT_LT(sfm::MatchDescriptors(a, c, sfm::MatchCriteria{}).size(), 5u);
}

TEST(ExactMatchingTest, TheAvx2KernelGivesThePortableOnesMatches) {
  if (std::string(sfm::AutoDotKernelName()) != "avx2")
    GTEST_SKIP() << "this build or CPU has no AVX2 kernel";
  std::mt19937 rng(11);
  // The dot products themselves, against plain sums, with row counts that
  // leave partial blocks (4 rows of a, 8 of b) and the extreme values.
  {
    const int na = 7, nb = 13, blocks = 2;
    std::uniform_int_distribution<int> byte(0, 255);
    std::vector<int16_t> a(na * 128), b(nb * 128), packed(blocks * sfm::kDotBlockValues, 0);
    for (auto& v : a) v = int16_t(byte(rng));
    for (auto& v : b) v = int16_t(byte(rng));
    std::fill(a.begin(), a.begin() + 128, int16_t(255));
    std::fill(b.end() - 128, b.end(), int16_t(255));
    for (int j = 0; j < nb; ++j)
      for (int k = 0; k < 128; ++k)
        packed[(j / 8) * sfm::kDotBlockValues + (k / 2) * 16 + (j % 8) * 2 + k % 2] =
            b[j * 128 + k];
    const size_t stride = 16;
    std::vector<int32_t> dots(na * stride, -1);
    sfm::DescriptorDotsAvx2(a.data(), na, packed.data(), blocks, dots.data(), stride);
    for (int i = 0; i < na; ++i)
      for (int j = 0; j < int(stride); ++j) {
        int32_t want = 0;
        for (int k = 0; j < nb && k < 128; ++k) want += a[i * 128 + k] * b[j * 128 + k];
        EXPECT_EQ(dots[i * stride + j], want) << i << ", " << j;
      }
    EXPECT_EQ(dots[nb - 1], 255 * 255 * 128);
  }
  // The matches, on SIFT-like descriptors some of which recur.
  for (const auto& [na, nb] : {std::pair{1, 1}, {7, 13}, {203, 97}, {64, 64}, {130, 1029}}) {
    sfm::ImageDescriptors a, b;
    a.rows = RandomDescriptors(na, &rng);
    b.rows = RandomDescriptors(nb, &rng);
    for (int j = 0; j < std::min(na, nb); j += 3) b.rows.row(j) = a.rows.row(j);
    const auto fast = sfm::MatchDescriptors(a, b, sfm::MatchCriteria{}, sfm::DotKernel::kAuto);
    const auto portable =
        sfm::MatchDescriptors(a, b, sfm::MatchCriteria{}, sfm::DotKernel::kPortable);
    EXPECT_EQ(fast, portable) << na << " x " << nb;
    EXPECT_GE(fast.size(), size_t((std::min(na, nb) + 2) / 3)) << na << " x " << nb;
  }
}

// COLMAP's table of verified pairs, and its id of the pair of images a < b.
constexpr char kTwoViewGeometriesTable[] =
    "CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT "
    "NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL);";
long ColmapPairId(long a, long b) { return a * 2147483647L + b; }

// A COLMAP-like database: images, keypoints and descriptors tables.
void MakeDatabase(const fs::path& file, const std::vector<std::pair<int, std::string>>& images,
                  int descriptor_bytes = 128) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  std::string sql =
      "CREATE TABLE images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, name TEXT "
      "NOT NULL UNIQUE, camera_id INTEGER NOT NULL);"
      "CREATE TABLE keypoints (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, "
      "cols INTEGER NOT NULL, data BLOB);"
      "CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, "
      "cols INTEGER NOT NULL, data BLOB);"
      "CREATE TABLE cameras (camera_id INTEGER PRIMARY KEY NOT NULL, model INTEGER NOT NULL, "
      "width INTEGER NOT NULL, height INTEGER NOT NULL, params BLOB, prior_focal_length "
      "INTEGER NOT NULL); INSERT INTO cameras VALUES (1, 0, 1600, 1200, NULL, 0);";
  for (const auto& [id, name] : images) {
    const std::string i = std::to_string(id);
    // One keypoint and one descriptor whose first byte is the id.
    char hex[3];
    std::snprintf(hex, sizeof hex, "%02x", id);
    sql += "INSERT INTO images VALUES (" + i + ", '" + name + "', 1);";
    sql += "INSERT INTO keypoints VALUES (" + i + ", 1, 4, x'" + std::string(hex) +
           std::string(30, '0') + "');";
    sql += "INSERT INTO descriptors VALUES (" + i + ", 1, 128, x'" + std::string(hex) +
           std::string(2 * descriptor_bytes - 2, '0') + "');";
  }
  char* error = nullptr;
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error), SQLITE_OK)
      << (error ? error : "");
  sqlite3_free(error);
  sqlite3_close(db);
}

TEST(ExactMatchingTest, ImagesAreNumberedByNameWithTheirFeatures) {
  TempDir tmp;
  const fs::path db = tmp.path() / "database.db";
  MakeDatabase(db, {{1, "view_02.jpg"}, {2, "view_00.jpg"}, {3, "view_01.jpg"}});
  sfm::NumberImagesByName(db);
  const std::vector<sfm::ImageDescriptors> images = sfm::ReadDatabaseDescriptors(db);
  ASSERT_EQ(images.size(), 3u);
  const char* names[] = {"view_00.jpg", "view_01.jpg", "view_02.jpg"};
  const int first_byte[] = {2, 3, 1};  // the old ids travel with the rows
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(images[k].image_id, k + 1);
    EXPECT_EQ(images[k].name, names[k]);
    ASSERT_EQ(images[k].rows.rows(), 1);
    EXPECT_EQ(images[k].rows(0, 0), first_byte[k]);
  }
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &raw), SQLITE_OK);
  sqlite3_stmt* stmt = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(raw,
                               "SELECT image_id, hex(substr(data, 1, 1)) FROM keypoints "
                               "ORDER BY image_id",
                               -1, &stmt, nullptr),
            SQLITE_OK);
  std::vector<std::string> keypoints;
  while (sqlite3_step(stmt) == SQLITE_ROW)
    keypoints.push_back(std::to_string(sqlite3_column_int(stmt, 0)) + ":" +
                        reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1)));
  sqlite3_finalize(stmt);
  sqlite3_close(raw);
  EXPECT_EQ(keypoints, (std::vector<std::string>{"1:02", "2:03", "3:01"}));
}

// Photos of two pages in one folder, and one photo of something else: the
// pairs COLMAP verified (15 matches and up, a geometry) link them into
// groups, largest first; a pair it found degenerate or too weak links none.
TEST(ExactMatchingTest, ViewsLinkedByVerifiedMatchesFallIntoGroups) {
  TempDir tmp;
  const fs::path db = tmp.path() / "database.db";
  MakeDatabase(db, {{1, "a0.jpg"},
                    {2, "a1.jpg"},
                    {3, "a2.jpg"},
                    {4, "b0.jpg"},
                    {5, "b1.jpg"},
                    {6, "b2.jpg"},
                    {7, "cat.jpg"}});
  std::string sql = kTwoViewGeometriesTable;
  auto pair = [&](long a, long b, int rows, int config) {
    sql += "INSERT INTO two_view_geometries VALUES (" + std::to_string(ColmapPairId(a, b)) + ", " +
           std::to_string(rows) + ", 2, NULL, " + std::to_string(config) + ");";
  };
  pair(1, 2, 400, 6);  // a0-a1-a2: a chain
  pair(2, 3, 15, 3);
  pair(1, 3, 0, 1);
  pair(4, 5, 900, 2);  // b0-b1, b1-b2
  pair(5, 6, 300, 4);
  pair(3, 4, 14, 3);  // too few to link a page to the other
  pair(6, 7, 80, 1);  // degenerate: no link
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(raw);
  using Groups = std::vector<std::vector<std::string>>;
  EXPECT_EQ(sfm::ViewsLinkedByMatches(db, 15),
            (Groups{{"a0.jpg", "a1.jpg", "a2.jpg"}, {"b0.jpg", "b1.jpg", "b2.jpg"}, {"cat.jpg"}}));
  EXPECT_EQ(sfm::ViewsLinkedByMatches(db, 14),
            (Groups{{"a0.jpg", "a1.jpg", "a2.jpg", "b0.jpg", "b1.jpg", "b2.jpg"}, {"cat.jpg"}}));
  EXPECT_EQ(
      sfm::ViewsLinkedByMatches(db, 500),
      (Groups{{"b0.jpg", "b1.jpg"}, {"a0.jpg"}, {"a1.jpg"}, {"a2.jpg"}, {"b2.jpg"}, {"cat.jpg"}}));
}

// Gives a database made by MakeDatabase 200 keypoints per image (x, y of
// each) and a two_view_geometries table: each pair (image ids, rows) has its
// first `rows` keypoints matched one to one as verified matches. `sql` runs
// first (cameras for the images, say).
void AddVerifiedMatches(const fs::path& db_file, const std::vector<std::vector<float>>& xy,
                        const std::vector<std::tuple<long, long, int>>& pairs,
                        const std::string& sql = "") {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(db_file.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(
                db, ("DELETE FROM keypoints;" + std::string(kTwoViewGeometriesTable) + sql).c_str(),
                nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_stmt* stmt = nullptr;
  ASSERT_EQ(
      sqlite3_prepare_v2(db, "INSERT INTO keypoints VALUES (?, 200, 6, ?)", -1, &stmt, nullptr),
      SQLITE_OK);
  for (size_t k = 0; k < xy.size(); ++k) {
    ASSERT_EQ(xy[k].size(), 400u);
    std::vector<float> rows;  // x, y and an identity affine shape (COLMAP's 6 columns)
    for (size_t i = 0; i < 200; ++i)
      rows.insert(rows.end(), {xy[k][2 * i], xy[k][2 * i + 1], 1, 0, 0, 1});
    sqlite3_bind_int(stmt, 1, int(k + 1));
    sqlite3_bind_blob(stmt, 2, rows.data(), int(rows.size() * sizeof(float)), SQLITE_TRANSIENT);
    EXPECT_EQ(sqlite3_step(stmt), SQLITE_DONE);
    sqlite3_reset(stmt);
  }
  sqlite3_finalize(stmt);
  std::vector<uint32_t> matches;
  for (uint32_t i = 0; i < 200; ++i) matches.insert(matches.end(), {i, i});
  ASSERT_EQ(sqlite3_prepare_v2(db, "INSERT INTO two_view_geometries VALUES (?, ?, 2, ?, 6)", -1,
                               &stmt, nullptr),
            SQLITE_OK);
  for (const auto& [a, b, rows] : pairs) {
    sqlite3_bind_int64(stmt, 1, ColmapPairId(a, b));
    sqlite3_bind_int(stmt, 2, rows);
    sqlite3_bind_blob(stmt, 3, matches.data(), int(rows * 2 * sizeof(uint32_t)), SQLITE_TRANSIENT);
    EXPECT_EQ(sqlite3_step(stmt), SQLITE_DONE);
    sqlite3_reset(stmt);
  }
  sqlite3_finalize(stmt);
  sqlite3_close(db);
}

// A phone's edited copy (the photo cropped, turned and scaled) is one shot
// with its photo: a similarity takes their matches onto each other. So is a
// scanner app's copy (the page cut out of the photo and straightened): a
// homography takes its whole frame inside the photo's, and inside the second
// view's. A second view of the page, a perspective map away with the
// table around the page in both, is not, nor is a pair with too few matches.
TEST(ExactMatchingTest, EditedAndScannedCopiesAreTheSameShotAndASecondViewIsNot) {
  TempDir tmp;
  const fs::path db_file = tmp.path() / "database.db";
  MakeDatabase(
      db_file,
      {{1, "IMG_0001.png"}, {2, "IMG_E0001.png"}, {3, "IMG_0002.png"}, {4, "Scan 2026-12-06.png"}});
  // The page in the photo, and the scan: that quadrilateral made the frame.
  const std::vector<cv::Point2f> page = {{300, 180}, {1280, 240}, {1330, 1010}, {250, 960}};
  const cv::Matx33f scan_from_photo(cv::getPerspectiveTransform(
      page, std::vector<cv::Point2f>{{0, 0}, {1000, 0}, {1000, 1400}, {0, 1400}}));
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> x(0, 1000), y(0, 1400);
  std::normal_distribution<float> noise(0, 0.3f);
  std::vector<cv::Point2f> photo;  // points on the page
  for (int i = 0; i < 200; ++i) {
    const cv::Vec3f p = scan_from_photo.inv() * cv::Vec3f(x(rng), y(rng), 1);
    photo.emplace_back(p[0] / p[2], p[1] / p[2]);
  }
  // The copy: the middle cropped, turned 90°, scaled by 1.3. The other view:
  // the page seen from elsewhere (a homography).
  const cv::Matx33f copy_from_photo(0, -1.3f, 1200 * 1.3f - 100, 1.3f, 0, -150, 0, 0, 1);
  const cv::Matx33f view_from_photo(0.9f, 0.12f, 40, -0.05f, 1.05f, 20, 4e-5f, 6e-5f, 1);
  std::vector<std::vector<float>> xy(4);
  for (const cv::Point2f& p : photo) {
    xy[0].insert(xy[0].end(), {p.x, p.y});
    for (const auto& [k, h] :
         {std::pair{1, copy_from_photo}, {2, view_from_photo}, {3, scan_from_photo}}) {
      const cv::Vec3f q = h * cv::Vec3f(p.x, p.y, 1);
      xy[size_t(k)].insert(xy[size_t(k)].end(),
                           {q[0] / q[2] + noise(rng), q[1] / q[2] + noise(rng)});
    }
  }
  // Every keypoint matched to its own, in each pair; 1-3 with 40 only. The
  // scan is 1000 x 1400.
  AddVerifiedMatches(
      db_file, xy, {{1, 2, 200}, {2, 3, 200}, {1, 3, 40}, {1, 4, 200}, {3, 4, 200}},
      "INSERT INTO cameras VALUES (2, 0, 1000, 1400, NULL, 0); UPDATE images SET camera_id = 2 "
      "WHERE image_id = 4;");

  sfm::SameShotOptions options;
  const std::vector<sfm::SameShot> shots = sfm::SameShots(db_file, options);
  ASSERT_EQ(shots.size(), 3u);
  EXPECT_EQ(shots[0].first, "IMG_0001.png");
  EXPECT_EQ(shots[0].second, "IMG_E0001.png");
  EXPECT_EQ(shots[0].matches, 200);
  EXPECT_GE(shots[0].share, 0.99);
  EXPECT_TRUE(shots[0].copy.empty()) << "a similarity";
  for (size_t i : {1, 2}) {
    EXPECT_EQ(shots[i].copy, "Scan 2026-12-06.png") << shots[i].first << " " << shots[i].second;
    EXPECT_GE(shots[i].share, 0.95);
  }
  // With few enough matches asked for, 1-3 is looked at too: still a second view.
  options.min_matches = 30;
  EXPECT_EQ(sfm::SameShots(db_file, options).size(), 3u);
}

// A second photo taken closer, from nearly straight above, of a creased page
// on a granite table: most matches lie on the table, whose plane a homography
// maps, and its frame lies inside the first photo's; but the page's matches
// stand off that plane by their parallax. A copy's matches all fit its map.
TEST(ExactMatchingTest, ACloserSecondPhotoOfACreasedPageOnATexturedTableIsNotACopy) {
  TempDir tmp;
  const fs::path db_file = tmp.path() / "database.db";
  MakeDatabase(db_file, {{1, "IMG_0001.png"}, {2, "IMG_0002.png"}});
  // The closer photo sees the middle of the first one's, enlarged 1.4 times.
  const cv::Matx33f closer_from_first(1.4f, 0.05f, -340, -0.04f, 1.4f, -230, 2e-5f, 1e-5f, 1);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> x(450, 1150), y(330, 870);
  std::normal_distribution<float> noise(0, 0.3f);
  std::vector<std::vector<float>> xy(2);
  for (int i = 0; i < 200; ++i) {
    const cv::Point2f p(x(rng), y(rng));
    const cv::Vec3f q = closer_from_first * cv::Vec3f(p.x, p.y, 1);
    // One in eight on the page, 6-30 px off the table's plane.
    const float parallax = i % 8 == 0 ? 6 + float(i % 25) : 0;
    xy[0].insert(xy[0].end(), {p.x, p.y});
    xy[1].insert(xy[1].end(), {q[0] / q[2] + noise(rng) + parallax, q[1] / q[2] + noise(rng)});
  }
  AddVerifiedMatches(db_file, xy, {{1, 2, 200}});
  EXPECT_TRUE(sfm::SameShots(db_file, sfm::SameShotOptions{}).empty());
}

TEST(ExactMatchingTest, BadDatabasesAreErrorsNamingTheFile) {
  TempDir tmp;
  const fs::path db = tmp.path() / "short.db";
  MakeDatabase(db, {{1, "a.jpg"}}, /*descriptor_bytes=*/100);
  try {
    sfm::ReadDatabaseDescriptors(db);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("short.db"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("a.jpg"), std::string::npos) << e.what();
  }
  const fs::path missing = tmp.path() / "missing.db";
  EXPECT_THROW(sfm::ReadDatabaseDescriptors(missing), std::runtime_error);
  EXPECT_FALSE(fs::exists(missing));  // read-only: not created
  const fs::path empty = tmp.path() / "empty.db";
  { std::ofstream(empty) << ""; }
  EXPECT_THROW(sfm::NumberImagesByName(empty), std::runtime_error);
}

}  // namespace
}  // namespace docunfold::testing
