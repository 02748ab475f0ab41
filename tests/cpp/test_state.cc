// The flat state: saved mid-run and restored into another data, the run
// goes on to the same bits.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "simloop/model.hpp"
#include "simloop/state.hpp"

namespace {

using simloop::Data;
using simloop::Model;

Model pusht() { return Model::from_file(std::string(SIMLOOP_TEST_SCENES) + "/pusht.xml"); }

// Steps `d` n times with every actuator at a fixed, different ctrl.
void drive(const Model& model, Data& d, int n) {
  const mjModel* m = model.get();
  for (int i = 0; i < m->nu; ++i) d.get()->ctrl[i] = 0.3 + 0.2 * i;
  for (int k = 0; k < n; ++k) mj_step(m, d.get());
}

TEST(State, LayoutCoversEveryPartInOrder) {
  const Model model = pusht();
  const mjModel* m = model.get();
  const auto layout = simloop::state_layout(m);
  ASSERT_EQ(layout.size(), 11u);
  EXPECT_EQ(layout[0].first, "time");
  EXPECT_EQ(layout[1], (std::pair<std::string, std::size_t>{"qpos", static_cast<std::size_t>(m->nq)}));
  EXPECT_EQ(layout[4].first, "qacc_warmstart");
  std::size_t total = 0;
  for (const auto& part : layout) total += part.second;
  EXPECT_EQ(total, simloop::state_size(m));
  EXPECT_EQ(total, 1 + 3u * m->nv + m->nq + m->na + m->nu + 6u * m->nbody + 7u * m->nmocap + m->nuserdata);
}

TEST(State, RestoredRunGoesOnBitForBit) {
  const Model model = pusht();
  const mjModel* m = model.get();
  Data original(model);
  mj_resetData(m, original.get());
  drive(model, original, 200);
  const std::vector<double> saved = simloop::get_state(m, original.get());
  drive(model, original, 300);

  Data restored(model);
  mj_resetData(m, restored.get());
  simloop::set_state(m, restored.get(), saved.data());
  EXPECT_EQ(simloop::get_state(m, restored.get()), saved);
  drive(model, restored, 300);
  EXPECT_EQ(0, std::memcmp(restored.get()->qpos, original.get()->qpos, sizeof(double) * m->nq));
  EXPECT_EQ(0, std::memcmp(restored.get()->qvel, original.get()->qvel, sizeof(double) * m->nv));
  EXPECT_EQ(restored.get()->time, original.get()->time);

  // The warmstart matters: restore without it and the bits differ, which is
  // why it is part of the state.
  std::vector<double> cold = saved;
  std::size_t at = 0;
  for (const auto& [name, size] : simloop::state_layout(m)) {
    if (name == "qacc_warmstart") std::fill_n(cold.begin() + static_cast<std::ptrdiff_t>(at), size, 0.0);
    at += size;
  }
  Data without(model);
  mj_resetData(m, without.get());
  simloop::set_state(m, without.get(), cold.data());
  drive(model, without, 300);
  EXPECT_NE(0, std::memcmp(without.get()->qpos, original.get()->qpos, sizeof(double) * m->nq));
}

}  // namespace
