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
  fs::create_directories(dir / (".out.tmp." + gone + ".1/colmap"));
  std::ofstream(dir / (".out.tmp." + gone + ".1/colmap/database.db")) << "x";
  { AtomicDirectory next(dir / "out"); }
  EXPECT_FALSE(fs::exists(dir / (".out.tmp." + gone + ".1")));
  EXPECT_TRUE(fs::exists(dir / "x.txt"));
  RemoveLeftBehind(dir / "none", ".out.tmp.");  // no such folder: nothing to do

  // A process killed and not yet reaped by its parent keeps its id: it writes nothing more.
  const pid_t zombie = ::fork();
  if (zombie == 0) ::_exit(0);
  ASSERT_GT(zombie, 0);
  const fs::path its = dir / (".out.tmp." + std::to_string(zombie) + ".1");
  fs::create_directories(its);
  siginfo_t info{};
  ASSERT_EQ(::waitid(P_PID, id_t(zombie), &info, WEXITED | WNOWAIT), 0);  // exited, not reaped
  RemoveLeftBehind(dir.path(), ".out.tmp.");
  EXPECT_FALSE(fs::exists(its));
  ASSERT_EQ(::waitpid(zombie, nullptr, 0), zombie);
}

TEST(AtomicFile, AFolderReplacesItsTargetWholeOrNotAtAll) {
  testing::TempDir dir;
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out/old.txt") << "an earlier run's";
  {
    AtomicDirectory staging(dir / "out/");  // a trailing slash names the same folder
    EXPECT_EQ(staging.path().parent_path(), fs::path(dir.path()));
    std::ofstream(staging.path() / "new.txt") << "half";
  }  // not committed: the earlier output stays, the folder is gone
  EXPECT_TRUE(fs::exists(dir / "out/old.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
  AtomicDirectory staging(dir / "out");
  std::ofstream(staging.path() / "new.txt") << "whole";
  staging.Commit();
  EXPECT_TRUE(fs::exists(dir / "out/new.txt"));
  EXPECT_FALSE(fs::exists(dir / "out/old.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
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
