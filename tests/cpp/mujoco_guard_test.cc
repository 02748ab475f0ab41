// MuJoCo's handlers (cpp/mujoco_guard.*): simloop's calls keep their own
// handling, and what the process's own MuJoCo code raises outside them goes
// where it would have gone without simloop.
//
// simloop installs its handlers once per process, keeping those it found, so
// each test runs in a fresh process of its own (gtest's "threadsafe" death
// test style re-executes this binary for the test alone) and exits 0 when
// everything held, or 1 after printing to stderr what did not.
#include "mujoco_guard.hpp"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "simloop/chapter_scene.hpp"
#include "simloop/sim.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

std::vector<std::string>& seen_warnings() {
  static std::vector<std::string> seen;
  return seen;
}
std::vector<std::string>& seen_errors() {
  static std::vector<std::string> seen;
  return seen;
}
// A user's error handler does not return (MuJoCo 4 ends the process if it
// does): it jumps back to where the user called MuJoCo.
std::jmp_buf* g_users_jump = nullptr;
extern "C" void users_warning(const char* message) { seen_warnings().emplace_back(message); }
extern "C" void users_error(const char* message) {
  seen_errors().emplace_back(message);
  if (g_users_jump != nullptr) std::longjmp(*g_users_jump, 1);
}

// The process's own MuJoCo code, outside simloop: a step of the chapter's
// model from a position MuJoCo rejects (it warns "Nan, Inf or huge value in
// QPOS" and resets the data).
void users_own_bad_step(const mjModel* m) {
  mjData* d = mj_makeData(m);
  d->qpos[0] = NAN;
  mj_step(m, d);
  mj_deleteData(d);
}

// The same bad step, through simloop: its warnings go to the Sim's own.
std::size_t simloops_bad_step(const simloop::Model& model) {
  simloop::Sim sim(model);
  sim.data()->qpos[0] = NAN;
  sim.step();
  return sim.warnings().size();
}

// Runs `test` and ends the process: 0 when everything held.
[[noreturn]] void exit_with(int (*test)()) { std::exit(test() == 0 ? 0 : 1); }

int check(bool ok, const char* what) {
  if (!ok) std::fprintf(stderr, "failed: %s\n", what);
  return ok ? 0 : 1;
}

int the_users_handlers_keep_what_is_raised_outside_simloop() {
  mju_user_warning = users_warning;
  mju_user_error = users_error;
  const simloop::Model model = simloop::pusher_scene();  // simloop installs its handlers here
  int failures = check(simloops_bad_step(model) >= 1, "simloop's step counted its warning");
  failures += check(seen_warnings().empty(), "simloop's own warning stayed simloop's");
  users_own_bad_step(model.get());
  failures += check(seen_warnings().size() == 1 && seen_warnings()[0].find("QPOS") != std::string::npos,
                    "the user's own warning reached the user's handler");
  std::jmp_buf jump;
  g_users_jump = &jump;
  if (setjmp(jump) == 0) mju_error("the user's own error");
  g_users_jump = nullptr;
  failures += check(seen_errors().size() == 1 && seen_errors()[0] == "the user's own error",
                    "the user's own error reached the user's handler");
  bool caught = false;
  try {
    simloop::detail::mujoco_call([] { mju_error("simloop's own error"); });
  } catch (const simloop::MujocoError&) {
    caught = true;
  }
  failures += check(caught && seen_errors().size() == 1, "simloop's own error stayed simloop's");
  return failures;
}

int without_a_handler_the_users_warning_gets_mujocos_default() {
  const test::TempDir dir;
  fs::current_path(dir.path());
  const simloop::Model model = simloop::pusher_scene();
  int failures = check(simloops_bad_step(model) >= 1, "simloop's step counted its warning");
  failures += check(!fs::exists("MUJOCO_LOG.TXT"), "simloop's own warning wrote no MUJOCO_LOG.TXT");
  users_own_bad_step(model.get());
  std::ifstream log("MUJOCO_LOG.TXT");
  std::stringstream text;
  text << log.rdbuf();
  failures += check(text.str().find("WARNING") != std::string::npos &&  // MuJoCo 4 puts the time after it
                        text.str().find("Nan, Inf or huge value in QPOS") != std::string::npos,
                    "the user's own warning went to MUJOCO_LOG.TXT, as MuJoCo's default does");
  std::fflush(stdout);
  fs::current_path("/");  // out of the directory, before it is removed
  return failures;
}

}  // namespace

TEST(MujocoGuard, TheUsersHandlersKeepWhatIsRaisedOutsideSimloopsCalls) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(exit_with(the_users_handlers_keep_what_is_raised_outside_simloop), testing::ExitedWithCode(0), "");
}

TEST(MujocoGuard, WithoutAHandlerTheUsersWarningsGetMujocosDefault) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(exit_with(without_a_handler_the_users_warning_gets_mujocos_default), testing::ExitedWithCode(0), "");
}
