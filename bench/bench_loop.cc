// The driver's loops against bare mj_step loops on the same scenes and
// inputs, side by side in one process: rounds alternate which goes first, and
// the medians (wall-clock and this thread's CPU time) and the medians of the
// per-round ratios are printed. Targets: the chapter's run (simloop::run, the
// default scenario) <= 1.03 x bare; a PushT scenario recording two bodies
// (run_scenario on tests/scenes/pusht.toml with record bodies tblock and
// pusher) <= 1.05 x a bare loop writing the same inputs on the same scene.
//
//   build/bench_loop [rounds=41] [steps=2000]
//   build/bench_loop --serve   one simloop::run (as sim_loop calls it) per
//                              line read from stdin; prints its seconds.
//                              bench/bench_python.py interleaves these with
//                              simloop.run() calls, so both see the same machine.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "simloop/model.hpp"
#include "simloop/run.hpp"
#include "simloop/scenario_run.hpp"

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The chapter's loop with nothing around it: no trajectory, no warning
// bookkeeping, no error guard.
[[gnu::noinline]] void bare_loop(const mjModel* m, mjData* d, const simloop::ChapterLayout& at,
                                 const simloop::Shove& shove, std::int64_t steps) {
  mj_resetData(m, d);
  mj_forward(m, d);
  double* force = d->xfrc_applied + 6 * at.box_body;
  for (std::int64_t step = 0; step < steps; ++step) {
    d->ctrl[0] = 1.0;
    force[0] = 0.0;
    force[1] = shove.acts_at(step) ? shove.force_y() : 0.0;
    force[2] = 0.0;
    mj_step(m, d);
  }
}

// The scenario's inputs written by hand, with nothing recorded: ctrl changes
// where the schedule changes it, each disturbance's wrench inside its window
// and an explicit zero outside it.
[[gnu::noinline]] void bare_scenario_loop(const mjModel* m, mjData* d, const simloop::Schedule& schedule) {
  mj_resetData(m, d);
  mj_forward(m, d);
  std::size_t next = 0;
  const auto& changes = schedule.control_changes;
  for (std::int64_t step = 0; step < schedule.steps; ++step) {
    for (; next < changes.size() && changes[next].step == step; ++next)
      d->ctrl[changes[next].actuator] = changes[next].value;
    for (const simloop::Schedule::Force& f : schedule.forces) {
      const bool acts = f.start <= step && step < f.end;
      for (int i = 0; i < 6; ++i) d->xfrc_applied[6 * f.body + i] = acts ? f.wrench[static_cast<size_t>(i)] : 0.0;
    }
    mj_step(m, d);
  }
}

double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Time {
  double wall = 0.0, cpu = 0.0;
};

template <class F>
Time timed(F&& f) {
  const double c0 = thread_cpu_seconds();
  const auto t0 = std::chrono::steady_clock::now();
  f();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return {wall, thread_cpu_seconds() - c0};
}

template <class F>
double seconds(F&& f) {
  return timed(std::forward<F>(f)).wall;
}

// Rounds of bare against driver, alternating which goes first.
struct Pairing {
  std::vector<double> bare_wall, bare_cpu, driver_wall, driver_cpu, wall_ratio, cpu_ratio;

  template <class Bare, class Driver>
  void rounds(int count, Bare&& bare, Driver&& driver) {
    for (int r = 0; r < count; ++r) {
      Time b, d;
      if (r % 2) {
        b = timed(bare);
        d = timed(driver);
      } else {
        d = timed(driver);
        b = timed(bare);
      }
      bare_wall.push_back(b.wall);
      bare_cpu.push_back(b.cpu);
      driver_wall.push_back(d.wall);
      driver_cpu.push_back(d.cpu);
      wall_ratio.push_back(d.wall / b.wall);
      cpu_ratio.push_back(d.cpu / b.cpu);
    }
  }

  void print(const char* bare_name, const char* driver_name, std::int64_t steps, double target) const {
    const double per_step = 1e6 / static_cast<double>(steps);
    std::printf("  %-34s wall median %8.3f ms (%5.2f us/step)  cpu median %8.3f ms\n", bare_name,
                median(bare_wall) * 1e3, median(bare_wall) * per_step, median(bare_cpu) * 1e3);
    std::printf("  %-34s wall median %8.3f ms (%5.2f us/step)  cpu median %8.3f ms\n", driver_name,
                median(driver_wall) * 1e3, median(driver_wall) * per_step, median(driver_cpu) * 1e3);
    std::printf("  driver / bare: %.4f wall, %.4f cpu (medians of per-round ratios; target <= %.2f)\n",
                median(wall_ratio), median(cpu_ratio), target);
  }
};

}  // namespace

int serve() {
  const simloop::Model model = simloop::pusher_scene();
  const simloop::RunConfig config;
  for (std::string line; std::getline(std::cin, line);) {
    simloop::RunResult result;
    const double s = seconds([&] { result = simloop::run(model, config); });
    std::printf("%.9f\n", s);
    std::fflush(stdout);
  }
  return 0;
}

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "--serve") == 0) return serve();
  const int rounds = argc > 1 ? std::atoi(argv[1]) : 41;
  const std::int64_t steps = argc > 2 ? std::atoll(argv[2]) : 2000;
  const simloop::Model model = simloop::pusher_scene();
  // One Data for both loops: two arenas would sit at different addresses,
  // and cache aliasing then biases one loop by several percent per process.
  simloop::Data data(model);
  simloop::Data& bare_data = data;
  simloop::Data& driver_data = data;
  simloop::RunConfig config;
  config.steps = steps;
  const simloop::Shove shove = simloop::draw_shove(config.seed, steps);

  // Same inputs, same physics: the two loops must end in the same state.
  bare_loop(model.get(), bare_data.get(), simloop::chapter_layout(model), shove, steps);
  double bare_qpos[8];
  std::memcpy(bare_qpos, bare_data.get()->qpos, sizeof bare_qpos);
  const simloop::RunResult check = simloop::run(model, config, driver_data);
  const bool same = std::memcmp(bare_qpos, driver_data.get()->qpos, sizeof bare_qpos) == 0;

  Pairing chapter;
  simloop::RunResult sink;
  chapter.rounds(
      rounds, [&] { bare_loop(model.get(), bare_data.get(), simloop::chapter_layout(model), shove, steps); },
      [&] { sink = simloop::run(model, config, driver_data); });
  std::printf("bench_loop: %d rounds of %lld steps each\n", rounds, static_cast<long long>(steps));
  std::printf("the chapter's run (%lld rows), %s\n", static_cast<long long>(check.trajectory.rows()),
              same ? "final states identical" : "FINAL STATES DIFFER");
  chapter.print("bare mj_step loop", "simloop::run (recording)", steps, 1.03);

  // PushT: its scenario file, recording the T-block and the pusher.
  simloop::Scenario pusht = simloop::Scenario::from_toml_file(SIMLOOP_BENCH_SCENES "/pusht.toml");
  pusht.record = simloop::RecordSpec{};
  pusht.record.bodies = {"tblock", "pusher"};
  const simloop::Model pusht_scene = simloop::load_scene(pusht);
  simloop::Data pusht_data(pusht_scene);
  simloop::ScenarioConfig pusht_config;
  pusht_config.steps = steps;
  const simloop::RunRecord pusht_check = simloop::run_scenario(pusht_scene, pusht, pusht_config, &pusht_data);
  std::vector<double> pusht_qpos(pusht_data.get()->qpos, pusht_data.get()->qpos + pusht_scene.get()->nq);
  bare_scenario_loop(pusht_scene.get(), pusht_data.get(), pusht_check.schedule);
  const bool pusht_same =
      std::memcmp(pusht_qpos.data(), pusht_data.get()->qpos, sizeof(double) * pusht_qpos.size()) == 0;
  Pairing scenario;
  simloop::RunRecord pusht_sink;
  scenario.rounds(
      rounds, [&] { bare_scenario_loop(pusht_scene.get(), pusht_data.get(), pusht_check.schedule); },
      [&] { pusht_sink = simloop::run_scenario(pusht_scene, pusht, pusht_config, &pusht_data); });
  std::printf("PushT scenario recording tblock and pusher (%lld rows of %zu columns), %s\n",
              static_cast<long long>(pusht_check.rows), pusht_check.columns.size(),
              pusht_same ? "final states identical" : "FINAL STATES DIFFER");
  scenario.print("bare mj_step loop, same inputs", "run_scenario (recording)", steps, 1.05);
  return same && pusht_same ? 0 : 1;
}
