#include "common/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

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

// A run killed half way (Ctrl-C) leaves its temporary behind; the next
// output to that place removes it, but not a running process's.
TEST(AtomicFile, WhatAKilledRunLeftIsRemovedNextTime) {
  testing::TempDir dir;
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);  // a process id no longer running
  const std::string gone = std::to_string(child);
  std::ofstream(dir / (".x.tmp." + gone + ".txt")) << "partial";
  std::ofstream(dir / ".x.tmp.1.txt") << "being written by a running process";
  std::ofstream(dir / (".y.tmp." + gone + ".txt")) << "another output's";
  std::ofstream(dir / ".x.tmp.notes.txt") << "a user's file";
  WriteTextAtomic(dir / "x.txt", "whole");
  EXPECT_FALSE(fs::exists(dir / (".x.tmp." + gone + ".txt")));
  EXPECT_TRUE(fs::exists(dir / ".x.tmp.1.txt"));
  EXPECT_TRUE(fs::exists(dir / (".y.tmp." + gone + ".txt")));
  EXPECT_TRUE(fs::exists(dir / ".x.tmp.notes.txt"));
  // A whole folder, as a stage's staging folder.
  fs::create_directories(dir / (".out.tmp-" + gone + "-123/colmap"));
  std::ofstream(dir / (".out.tmp-" + gone + "-123/colmap/database.db")) << "x";
  RemoveLeftBehind(dir.path(), ".out.tmp-");
  EXPECT_FALSE(fs::exists(dir / (".out.tmp-" + gone + "-123")));
  EXPECT_TRUE(fs::exists(dir / "x.txt"));
  RemoveLeftBehind(dir / "none", ".out.tmp-");  // no such folder: nothing to do
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
