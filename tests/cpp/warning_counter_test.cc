// Counting MuJoCo's warnings past 2^31 (detail::WarningCounter), and the
// counts' text, which must read as it did when they were ints.
#include "warning_counter.hpp"

#include <gtest/gtest.h>

#include <climits>
#include <cstdint>
#include <memory>

#include "simloop/output.hpp"

namespace {

TEST(WarningCounter, CountsPastTwoToTheThirtyFirstWithoutOverflow) {
  // Only mjData's warning counters are read: a zeroed mjData stands for a
  // step that raised INT_MAX warnings of one kind, three times over.
  auto data = std::make_unique<mjData>();
  simloop::detail::WarningCounter counter;
  for (std::int64_t step = 5; step < 8; ++step) {
    data->warning[mjWARN_BADQACC].number = INT_MAX;
    data->warning[mjWARN_BADQACC].lastinfo = 2;
    counter.after_step(data.get(), step);
    EXPECT_EQ(data->warning[mjWARN_BADQACC].number, 0);  // emptied into the counter
  }
  const std::vector<simloop::Warning> warnings = counter.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].name, "mjWARN_BADQACC");
  EXPECT_EQ(warnings[0].count, std::int64_t{3} * INT_MAX);
  EXPECT_GT(warnings[0].count, std::int64_t{INT32_MAX});
  EXPECT_EQ(warnings[0].first_step, 5);
  EXPECT_EQ(simloop::warning_line(warnings[0]),
            "MuJoCo warning mjWARN_BADQACC: raised 6442450941 times, first in step 5: " + warnings[0].message + "\n");
}

TEST(WarningCounter, AWarningOnceReadsAsBefore) {
  auto data = std::make_unique<mjData>();
  simloop::detail::WarningCounter counter;
  data->warning[mjWARN_BADQPOS].number = 1;
  counter.after_step(data.get(), 0);
  const std::vector<simloop::Warning> warnings = counter.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].count, 1);
  EXPECT_NE(simloop::warning_line(warnings[0]).find(": raised 1 time, first in step 0: "), std::string::npos);
}

}  // namespace
