// The driver's loop against a bare mj_step loop on the same scene and inputs,
// side by side in one process: rounds alternate which goes first, and the
// medians and their ratio are printed. Target: driver <= 1.03 x bare.
//
//   build/bench_loop [rounds=41] [steps=2000]
//   build/bench_loop --serve   one simloop::run (as sim_loop calls it) per
//                              line read from stdin; prints its seconds.
//                              bench/bench_python.py interleaves these with
//                              simloop.run() calls, so both see the same machine.
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

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The chapter's loop with nothing around it: no trajectory, no warning
// bookkeeping, no error guard.
[[gnu::noinline]] void bare_loop(const mjModel* m, mjData* d, const simloop::SceneLayout& at, const simloop::Shove& shove,
               std::int64_t steps) {
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

template <class F>
double seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int serve() {
  const simloop::Model model = simloop::Model::pusher_scene();
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
  const simloop::Model model = simloop::Model::pusher_scene();
  // One Data for both loops: two arenas would sit at different addresses,
  // and cache aliasing then biases one loop by several percent per process.
  simloop::Data data(model);
  simloop::Data& bare_data = data;
  simloop::Data& driver_data = data;
  simloop::RunConfig config;
  config.steps = steps;
  const simloop::Shove shove = simloop::draw_shove(config.seed, steps);

  // Same inputs, same physics: the two loops must end in the same state.
  bare_loop(model.get(), bare_data.get(), model.layout(), shove, steps);
  double bare_qpos[8];
  std::memcpy(bare_qpos, bare_data.get()->qpos, sizeof bare_qpos);
  const simloop::RunResult check = simloop::run(model, config, driver_data);
  const bool same = std::memcmp(bare_qpos, driver_data.get()->qpos, sizeof bare_qpos) == 0;

  std::vector<double> bare, driver, ratio;
  simloop::RunResult sink;
  for (int r = 0; r < rounds; ++r) {
    double b = 0, d = 0;
    const auto time_bare = [&] { b = seconds([&] { bare_loop(model.get(), bare_data.get(), model.layout(), shove, steps); }); };
    const auto time_driver = [&] { d = seconds([&] { sink = simloop::run(model, config, driver_data); }); };
    if (r % 2) {
      time_bare();
      time_driver();
    } else {
      time_driver();
      time_bare();
    }
    bare.push_back(b);
    driver.push_back(d);
    ratio.push_back(d / b);
  }
  std::printf("bench_loop: %d rounds of %lld steps, %s\n", rounds, static_cast<long long>(steps),
              same ? "final states identical" : "FINAL STATES DIFFER");
  std::printf("  bare mj_step loop          median %.3f ms  (%.2f us/step)\n", median(bare) * 1e3,
              median(bare) * 1e6 / static_cast<double>(steps));
  std::printf("  simloop::run (recording)   median %.3f ms  (%.2f us/step, %lld rows)\n", median(driver) * 1e3,
              median(driver) * 1e6 / static_cast<double>(steps), static_cast<long long>(check.trajectory.rows()));
  std::printf("  driver / bare: %.4f (median of per-round ratios; target <= 1.03)\n", median(ratio));
  return same ? 0 : 1;
}
