// simloop._core's Episodes, their state seen from Python: each episode's
// mjData and mjModel arrays as numpy views, what simloop.physics names for
// the environments' hooks. Glue only: the arrays and what fills them are
// the library's (Episodes::data_field, fields.hpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>  // (std::optional arguments)

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "bindings_sim.hpp"
#include "simloop/episode.hpp"
#include "simloop/fields.hpp"
#include "simloop/model.hpp"
#include "simloop/object_names.hpp"
#include "simloop/scenario.hpp"

namespace simloop_py {

using namespace pybind11::literals;

void bind_episode_state(py::class_<PyEpisodes>& episodes) {
  // A view's base is these Episodes (or a holder of the episode's model):
  // no view outlives what it reads. Each episode's mjData stays where it is
  // from construction on; the contacts' and constraints' arrays hold the
  // rows in use when taken, so a hook takes its views afresh at each call.
  episodes
      .def(
          "data_field",
          [](const py::object& self, std::size_t i, const std::string& name, bool staged) {
            PyEpisodes& e = self.cast<PyEpisodes&>();
            EpisodesLock lock(e);
            // A staged start's arrays are the hook's to write (Episodes::stage_reset).
            return staged ? field_view(e.episodes.staged_field(i, name), self, true)
                          : field_view(e.episodes.data_field(i, name), self, false);
          },
          "i"_a, "name"_a, "staged"_a = false,
          "A read-only numpy view of episode i's mjData array (keeps the Episodes alive); staged: a writable "
          "one of its staged start's.")
      .def(
          "model_field",
          [](PyEpisodes& e, std::size_t i, const std::string& name, bool staged) {
            EpisodesLock lock(e);
            const simloop::Model& model = staged ? e.episodes.staged_model(i) : e.episodes.model(i);
            return field_view(simloop::model_field(model.get(), name), model_owner(model), false);
          },
          "i"_a, "name"_a, "staged"_a = false,
          "A read-only numpy view of episode i's mjModel array (its scene parameters' copy; staged: its staged "
          "start's).")
      .def(
          "model_of",
          [](PyEpisodes& e, std::size_t i, bool staged) {
            EpisodesLock lock(e);
            return staged ? e.episodes.staged_model(i) : e.episodes.model(i);
          },
          "i"_a, "staged"_a = false,
          "Episode i's model: the shared one, or its copy with the episode's scene parameters (staged: its "
          "staged start's).")
      .def(
          "field_rows",
          [](PyEpisodes& e, const std::string& owner, const std::string& name) {
            EpisodesLock lock(e);
            const mjModel* m = e.episodes.model().get();
            return field_rows(owner == "model" ? simloop::model_field(m, name)
                                               : simloop::data_field(m, e.episodes.data(0), name));
          },
          "owner"_a, "name"_a, "(rows_count, kind of object a row is or '') of a model or data array.")
      // reset in two calls around an on_reset hook (Episodes::stage_reset): the hook runs in Python between
      // them, with no lock held, so that it may read and write the staged start through these.
      .def(
          "stage_reset",
          [](PyEpisodes& e, std::size_t i, std::uint64_t seed, const std::optional<std::string>& reset) {
            EpisodesLock lock(e);
            std::optional<simloop::ResetSpec> spec;
            if (reset) spec = simloop::reset_over(e.episodes.scenario().reset, *reset, "reset options");
            e.episodes.stage_reset(i, seed, spec ? &*spec : nullptr);
          },
          "i"_a, "seed"_a, "reset"_a = py::none())
      .def(
          "commit_reset",
          [](PyEpisodes& e, std::size_t i) {
            EpisodesLock lock(e);
            const auto width = static_cast<std::size_t>(e.episodes.width());
            if (i >= e.episodes.count()) throw py::index_error("episode " + std::to_string(i) + " does not exist");
            double* row = e.observations.data() + i * width;
            e.episodes.commit_reset(i, row);
            return vec(row + kRowLabels, width - kRowLabels);
          },
          "i"_a)
      .def(
          "drawn",
          [](PyEpisodes& e, std::size_t i) {
            EpisodesLock lock(e);
            const simloop::Schedule::Start& start = e.episodes.start(i);
            py::dict out;
            if (start.keyframe >= 0) {
              out["keyframe"] = simloop::object_name(e.episodes.model().get(), mjOBJ_KEY, start.keyframe);
            }
            for (const auto& [name, value] : simloop::drawn_columns(start)) out[py::str(name)] = value;
            return out;
          },
          "i"_a, "What episode i's start drew: its keyframe's name if any, then drawn_columns' values by name.");
}

}  // namespace simloop_py
