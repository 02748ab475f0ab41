// Results as bytes and back, every double with the same bits: how a run's
// record, a chapter's result or a sweep crosses to another process (Python
// pickles them this way, a cluster's workers send them home).
//
// The bytes start with kRecordBytesVersion (a uint32) and what they hold (a
// uint8), then the fields in order, in the machine's byte order (the bytes
// go between processes of one simloop build, not into files). Reading
// checks everything it takes: bytes that are cut short, too long, of
// another version or kind, or whose counts ask for more than the bytes
// left (so bad bytes cannot ask for huge memory) throw InvalidArgument,
// one line naming what could not be read. The messages speak of
// unpickling, as Python's pickle is where people meet them, and name the
// classes as Python does: a RunRecord is a ScenarioResult there.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "simloop/run.hpp"
#include "simloop/run_record.hpp"
#include "simloop/sweep.hpp"

namespace simloop {

// Bump when any result's fields change. 4: the version moved into the
// bytes, each struct written field by field (3 was Python's (3, fields)).
inline constexpr std::uint32_t kRecordBytesVersion = 7;  // 7: a model value's field and index

[[nodiscard]] std::string to_bytes(const RunRecord& record);
[[nodiscard]] std::string to_bytes(const RunResult& result);  // the record's fields, then the chapter's report
[[nodiscard]] std::string to_bytes(const SweepResult& result);

[[nodiscard]] RunRecord record_from_bytes(std::string_view bytes);
[[nodiscard]] RunResult run_result_from_bytes(std::string_view bytes);
// The points as measured; stable and the edge are judged again (judge_sweep)
// rather than stored, so they cannot disagree with the points.
[[nodiscard]] SweepResult sweep_result_from_bytes(std::string_view bytes);

}  // namespace simloop
