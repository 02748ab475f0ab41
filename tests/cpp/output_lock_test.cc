// OutputLock: one run at a time in a folder; another process is refused,
// naming the holder.
#include "simloop/output_lock.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>

#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

// What a forked child got trying to lock `dir`: 0 locked, 1 OutputInUse
// whose message names this process's pid, 2 another error or message.
int lock_in_a_child(const fs::path& dir) {
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    try {
      const simloop::OutputLock lock(dir);
      ::_exit(0);
    } catch (const simloop::OutputInUse& e) {
      const std::string expected = dir.string() + ": another simloop run (pid " + std::to_string(parent) +
                                   ") is writing in this folder; wait for it to end, or choose another folder";
      ::_exit(e.what() == expected ? 1 : 2);
    } catch (...) {
      ::_exit(2);
    }
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(OutputLock, AnotherProcessIsRefusedNamingTheHolderUntilTheLastHolderLetsGo) {
  test::TempDir dir;
  EXPECT_EQ(lock_in_a_child(dir.path()), 0);
  {
    const simloop::OutputLock first(dir.path());
    EXPECT_EQ(lock_in_a_child(dir.path()), 1);
    {
      // Shared within the process: a second lock on the folder adds a reference.
      const simloop::OutputLock second(dir.path());
      simloop::OutputWriter writer(dir.path());  // takes it too
    }
    EXPECT_EQ(lock_in_a_child(dir.path()), 1) << "released while the first still held it";
  }
  EXPECT_EQ(lock_in_a_child(dir.path()), 0);
}

TEST(OutputLock, AFolderThatCannotBeOpenedIsAnIoErrorNamingIt) {
  test::TempDir dir;
  try {
    const simloop::OutputLock lock(dir.path() / "missing");
    FAIL() << "locked a folder that does not exist";
  } catch (const simloop::IoError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir.path() / "missing").string() + ": cannot open the folder", 0), 0u)
        << e.what();
  }
}

}  // namespace
