#include "common/atomic_file.h"

#include <gtest/gtest.h>

#include <fstream>

#include "common/errors.h"
#include "tests/support/test_support.h"

namespace docunfold {
namespace {

TEST(AtomicFile, LeavesNoTemporaryOnFailure) {
  testing::TempDir dir;
  {
    AtomicOutput out(dir / "sub" / "x.txt");
    std::ofstream(out.temp_path()) << "partial";
    // No Commit: simulates a stage that fails half way.
  }
  EXPECT_FALSE(fs::exists(dir / "sub" / "x.txt"));
  EXPECT_TRUE(fs::is_empty(dir / "sub"));
  WriteTextAtomic(dir / "sub" / "x.txt", "whole");
  std::ifstream f(dir / "sub" / "x.txt");
  std::string s;
  f >> s;
  EXPECT_EQ(s, "whole");
}

TEST(AtomicFile, UnwritableDirectoryIsAnOutputError) {
  testing::TempDir dir;
  std::ofstream(dir / "file") << "x";
  EXPECT_THROW(WriteTextAtomic(dir / "file" / "y.txt", "y"), OutputError);
}

TEST(AtomicFile, ImagesRoundTripAndBadImagesAreInputErrors) {
  testing::TempDir dir;
  cv::Mat img(10, 20, CV_8UC3, cv::Scalar(1, 2, 3));
  WriteImageAtomic(dir / "a.png", img);
  cv::Mat back = ReadImage(dir / "a.png");
  EXPECT_EQ(cv::norm(img, back, cv::NORM_INF), 0);
  std::ofstream(dir / "bad.jpg") << "not a jpeg";
  EXPECT_THROW(ReadImage(dir / "bad.jpg"), InputError);
  EXPECT_THROW(ReadImage(dir / "none.jpg"), InputError);
}

}  // namespace
}  // namespace docunfold
