#include "simloop/batch.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <map>
#include <string>
#include <thread>

#include "simloop/errors.hpp"

namespace simloop {

int batch_workers(int threads, std::size_t jobs) noexcept {
  const int wanted = threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(wanted), std::max<std::size_t>(jobs, 1)));
}

std::vector<RunResult> run_batch(const Model& model, const std::vector<RunConfig>& configs, int threads) {
  if (threads < 0) {
    throw InvalidArgument("threads must be at least 1, or 0 for one per core, got " + std::to_string(threads));
  }
  for (std::size_t i = 0; i < configs.size(); ++i) {
    try {
      validate(configs[i]);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("run " + std::to_string(i) + ": " + e.what());
    }
  }
  // The model is frozen while stepping, so each setting (timestep, energy)
  // gets its own copy, made here, before the workers share them.
  std::map<std::pair<double, bool>, Model> models;
  std::vector<const Model*> model_of(configs.size());
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const std::pair<double, bool> key{configs[i].timestep, configs[i].audit_energy};
    auto it = models.find(key);
    if (it == models.end()) it = models.emplace(key, model.for_run(key.first, key.second)).first;
    model_of[i] = &it->second;
  }

  const int workers = batch_workers(threads, configs.size());
  std::vector<Data> datas;
  datas.reserve(static_cast<std::size_t>(workers));
  for (int w = 0; w < workers; ++w) datas.emplace_back(model);

  std::vector<RunResult> results(configs.size());
  std::vector<std::exception_ptr> errors(configs.size());
  std::atomic<std::size_t> next{0};
  const auto work = [&](Data& data) noexcept {
    for (std::size_t i; (i = next.fetch_add(1)) < configs.size();) {
      try {
        results[i] = run(*model_of[i], configs[i], data);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(workers - 1));
  for (int w = 1; w < workers; ++w) pool.emplace_back(work, std::ref(datas[static_cast<std::size_t>(w)]));
  work(datas[0]);  // the calling thread is worker 0
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return results;
}

}  // namespace simloop
