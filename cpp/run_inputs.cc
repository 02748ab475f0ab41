// The caller's own inputs to a run (RunInputs, recorder.hpp): Python's
// arrays split into each run's slice, and checked against the run's scene
// and length before any step.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/recorder.hpp"
#include "simloop/state.hpp"

namespace simloop {

void check_inputs(const mjModel* m, const RunInputs& inputs, std::int64_t steps) {
  if (inputs.controls && inputs.policy) {
    throw InvalidArgument("controls and a policy both decide ctrl: give one of them");
  }
  if (inputs.controls) {
    if (inputs.control_steps != steps || inputs.control_width != m->nu) {
      throw InvalidArgument("controls must have one row per step and one column per actuator, (" +
                            std::to_string(steps) + ", " + std::to_string(m->nu) + ") for this run, got (" +
                            std::to_string(inputs.control_steps) + ", " + std::to_string(inputs.control_width) + ")");
    }
    const std::size_t count = static_cast<std::size_t>(steps) * static_cast<std::size_t>(m->nu);
    const double* bad =
        std::find_if(inputs.controls, inputs.controls + count, [](double v) { return !std::isfinite(v); });
    if (bad != inputs.controls + count) {
      const std::size_t at = static_cast<std::size_t>(bad - inputs.controls);
      throw InvalidArgument("controls must be finite, got " + std::to_string(*bad) + " at step " +
                            std::to_string(at / static_cast<std::size_t>(m->nu)) + ", actuator " +
                            std::to_string(at % static_cast<std::size_t>(m->nu)));
    }
  }
  if (inputs.initial_state) {
    if (!takes_state_size(m, inputs.state_size)) {
      throw InvalidArgument("initial_state must hold " + state_sizes_text(m) + " for this scene, got " +
                            std::to_string(inputs.state_size));
    }
    const double* end = inputs.initial_state + inputs.state_size;
    const double* bad = std::find_if(inputs.initial_state, end, [](double v) { return !std::isfinite(v); });
    if (bad != end) {
      throw InvalidArgument("initial_state must be finite, got " + std::to_string(*bad) + " at index " +
                            std::to_string(bad - inputs.initial_state));
    }
  }
}

namespace {

// A shape as numpy prints one: (5,) or (2, 3).
std::string shape_text(const std::vector<std::int64_t>& shape) {
  std::string text;
  for (const std::int64_t n : shape) text += (text.empty() ? "" : ", ") + std::to_string(n);
  return "(" + text + (shape.size() == 1 ? ",)" : ")");
}

// How far apart runs' slices of `array` are: 0 when every run reads the
// whole array (it has a run's `dims`), else a run's size (it has one more,
// the runs). `shapes` names what it may be.
std::size_t run_stride(const char* name, const InputArray& array, std::size_t runs, bool batch, std::size_t dims,
                       const std::string& shapes, const char* per_run) {
  const std::size_t given = array.shape.size();
  if (given != dims && !(batch && given == dims + 1)) {
    throw InvalidArgument(std::string(name) + " must be shaped " + shapes + ", got shape " + shape_text(array.shape));
  }
  if (given == dims) return 0;
  if (static_cast<std::size_t>(array.shape.front()) != runs) {
    throw InvalidArgument(std::string(name) + ": " + std::to_string(array.shape.front()) + " " + per_run + " for " +
                          std::to_string(runs) + " runs");
  }
  std::size_t stride = 1;
  for (std::size_t d = 1; d < given; ++d) stride *= static_cast<std::size_t>(array.shape[d]);
  return stride;
}

}  // namespace

std::vector<RunInputs> split_inputs(std::size_t runs, bool batch, const std::optional<InputArray>& controls,
                                    const std::optional<InputArray>& initial_state) {
  std::vector<RunInputs> out(runs);
  if (controls) {
    const std::size_t stride = run_stride("controls", *controls, runs, batch, 2,
                                          batch ? "(runs, steps, nu) or (steps, nu)" : "(steps, nu)", "runs' controls");
    for (std::size_t i = 0; i < runs; ++i) {
      out[i].controls = controls->data + i * stride;
      out[i].control_steps = controls->shape[controls->shape.size() - 2];
      out[i].control_width = controls->shape.back();
    }
  }
  if (initial_state) {
    const std::size_t stride = run_stride("initial_state", *initial_state, runs, batch, 1,
                                          batch ? "(runs, state_size) or (state_size,)" : "(state_size,)", "states");
    for (std::size_t i = 0; i < runs; ++i) {
      out[i].initial_state = initial_state->data + i * stride;
      out[i].state_size = static_cast<std::size_t>(initial_state->shape.back());
    }
  }
  return out;
}

}  // namespace simloop
