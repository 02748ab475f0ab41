// Many runs over one compiled model, the chapter's "one model, many datas":
// run_scenario_batch (scenario_run.hpp) runs them; this is how many workers.
#pragma once

#include <cstddef>

namespace simloop {

// The worker count a batch uses for `threads` (0: one per core) and `jobs`.
[[nodiscard]] int batch_workers(int threads, std::size_t jobs) noexcept;

}  // namespace simloop
