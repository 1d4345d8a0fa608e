// write_file_atomically: complete file or no change, never a leftover temporary.
#include <gtest/gtest.h>

#include <stdexcept>

#include "io/atomic_file.h"
#include "io/input_error.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using subd2nurbs::testing::read_text;
using subd2nurbs::testing::TempDir;

TEST(AtomicFile, WritesNewFile) {
  TempDir dir;
  const std::string path = dir.file("out.txt");
  write_file_atomically(path, [](std::ostream& out) { out << "hello\n"; });
  EXPECT_EQ(read_text(path), "hello\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, ReplacesExistingFile) {
  TempDir dir;
  const std::string path = dir.write("out.txt", "old content that is longer\n");
  write_file_atomically(path, [](std::ostream& out) { out << "new\n"; });
  EXPECT_EQ(read_text(path), "new\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, MissingDirectoryThrowsWriteErrorAndLeavesNothing) {
  TempDir dir;
  const std::string path = dir.file("no/such/dir/out.txt");
  try {
    write_file_atomically(path, [](std::ostream& out) { out << "x"; });
    FAIL() << "no exception";
  } catch (const WriteError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_TRUE(dir.entries().empty());
}

TEST(AtomicFile, ThrowingWriterKeepsExistingFileIntact) {
  TempDir dir;
  const std::string path = dir.write("out.txt", "precious\n");
  EXPECT_THROW(write_file_atomically(path,
                                     [](std::ostream& out) {
                                       out << "partial";
                                       out.flush();
                                       throw std::runtime_error("writer failed");
                                     }),
               std::runtime_error);
  EXPECT_EQ(read_text(path), "precious\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, StreamFailureThrowsWriteError) {
  TempDir dir;
  const std::string path = dir.write("out.txt", "precious\n");
  EXPECT_THROW(write_file_atomically(path,
                                     [](std::ostream& out) {
                                       out << "partial";
                                       out.setstate(std::ios::badbit);  // as after an I/O error
                                     }),
               WriteError);
  EXPECT_EQ(read_text(path), "precious\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, TargetIsADirectoryThrowsWriteError) {
  TempDir dir;
  std::filesystem::create_directory(dir.path() / "sub");
  EXPECT_THROW(write_file_atomically(dir.file("sub"), [](std::ostream& out) { out << "x"; }),
               WriteError);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"sub"});
}
