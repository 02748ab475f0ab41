// PipedFile: a file another library writes through a pipe, written and
// checked here; every byte put in place, a write error kept for finish(), a
// writer never blocked.
#include "simloop/piped_file.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <string>

#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

TEST(PipedFile, EveryByteTheWriterSendsIsPutInPlace) {
  test::TempDir dir;
  const fs::path target = dir.path() / "out.bin";
  simloop::PipedFile file(target);
  const int writer = ::open(file.writer_path().c_str(), O_WRONLY | O_CLOEXEC);
  ASSERT_GE(writer, 0);
  file.close_writer();
  std::string sent;
  for (int i = 0; i < 200; ++i) sent += std::string(10007, static_cast<char>('a' + i % 26));
  ASSERT_EQ(::write(writer, sent.data(), sent.size()), static_cast<ssize_t>(sent.size()));
  EXPECT_FALSE(file.wait_for_end(std::chrono::milliseconds(50))) << "ended while the writer was open";
  ::close(writer);
  ASSERT_TRUE(file.wait_for_end(std::chrono::seconds(10)));
  EXPECT_EQ(file.bytes_written(), static_cast<std::int64_t>(sent.size()));
  file.finish();
  EXPECT_FALSE(fs::exists(target)) << "in place before the commit";
  simloop::commit_together({&file.pending()});
  EXPECT_EQ(test::read_text(target), sent);
}

TEST(PipedFile, AWriteErrorIsKeptForFinishAndTheWriterIsNeverBlocked) {
  test::TempDir dir;
  const pid_t pid = ::fork();
  if (pid == 0) {
    struct rlimit limit {
      64 * 1024, RLIM_INFINITY
    };
    ::setrlimit(RLIMIT_FSIZE, &limit);
    ::signal(SIGXFSZ, SIG_IGN);
    int code = 0;
    {
      simloop::PipedFile file(dir.path() / "out.bin");
      const int writer = ::open(file.writer_path().c_str(), O_WRONLY | O_CLOEXEC);
      file.close_writer();
      const std::string block(16384, 'x');
      for (int i = 0; i < 64 && code == 0; ++i) {
        if (::write(writer, block.data(), block.size()) != static_cast<ssize_t>(block.size())) code = 3;
      }
      ::close(writer);
      if (code == 0 && !file.wait_for_end(std::chrono::seconds(10))) code = 4;
      try {
        if (code == 0) {
          file.finish();
          code = 5;
        }
      } catch (const simloop::IoError& e) {
        const std::string expected = (dir.path() / "out.bin").string() + ": cannot write (File too large)";
        code = e.what() == expected ? 0 : 6;
      }
    }  // the temporary file goes here
    ::_exit(code);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_TRUE(fs::is_empty(dir.path())) << "the temporary file was left";
}

TEST(PipedFile, DestroyedBeforeTheWriterClosedItLeavesNoFileAndTheWriterGoesOn) {
  test::TempDir dir;
  int writer = -1;
  {
    simloop::PipedFile file(dir.path() / "out.bin");
    writer = ::open(file.writer_path().c_str(), O_WRONLY | O_CLOEXEC);
    ASSERT_GE(writer, 0);
    file.close_writer();
    ASSERT_EQ(::write(writer, "abc", 3), 3);
  }
  EXPECT_TRUE(fs::is_empty(dir.path())) << "the temporary file was left";
  // The pipe is still drained: far more than its 64 KiB, no EPIPE, no block.
  const std::string block(1 << 20, 'y');
  for (int i = 0; i < 8; ++i) {
    EXPECT_EQ(::write(writer, block.data(), block.size()), static_cast<ssize_t>(block.size()));
  }
  ::close(writer);
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
