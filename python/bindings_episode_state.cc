// simloop._core's Episodes, their state seen from Python: each episode's
// mjData and mjModel arrays as numpy views, what simloop.physics names for
// the environments' hooks. Glue only: the arrays and what fills them are
// the library's (Episodes::data_field, fields.hpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <string>

#include "bindings_sim.hpp"
#include "simloop/episode.hpp"
#include "simloop/fields.hpp"
#include "simloop/model.hpp"

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
          [](const py::object& self, std::size_t i, const std::string& name) {
            PyEpisodes& e = self.cast<PyEpisodes&>();
            EpisodesLock lock(e);
            return field_view(e.episodes.data_field(i, name), self, false);
          },
          "i"_a, "name"_a, "A read-only numpy view of episode i's mjData array (keeps the Episodes alive).")
      .def(
          "model_field",
          [](PyEpisodes& e, std::size_t i, const std::string& name) {
            EpisodesLock lock(e);
            const simloop::Model& model = e.episodes.model(i);
            return field_view(simloop::model_field(model.get(), name), model_owner(model), false);
          },
          "i"_a, "name"_a, "A read-only numpy view of episode i's mjModel array (its scene parameters' copy).")
      .def(
          "model_of",
          [](PyEpisodes& e, std::size_t i) {
            EpisodesLock lock(e);
            return e.episodes.model(i);
          },
          "i"_a, "Episode i's model: the shared one, or its copy with the episode's scene parameters.")
      .def(
          "field_rows",
          [](PyEpisodes& e, const std::string& owner, const std::string& name) {
            EpisodesLock lock(e);
            const mjModel* m = e.episodes.model().get();
            return field_rows(owner == "model" ? simloop::model_field(m, name)
                                               : simloop::data_field(m, e.episodes.data(0), name));
          },
          "owner"_a, "name"_a, "(rows_count, kind of object a row is or '') of a model or data array.");
}

}  // namespace simloop_py
