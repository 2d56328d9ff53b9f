// A damaged rawlog in `upd playback` (a file cut off by a power loss, garbage mid-stream): the
// observations read before the first object that fails to deserialize are intact, so playback
// keeps their maps, records where the damage starts in summary.json and exits with
// kExitPartial. `--strict` turns the damage back into an error (exit 1, nothing written).
#pragma once

#include "upd/mrpt_bridge/rawlog_reader.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

namespace upd::app {

/// Exit status of `upd playback` when the rawlog is damaged and the maps of the observations
/// before the damage were written (0: done, 1: failed and nothing written, 2: usage).
constexpr int kExitPartial = 3;

struct RawlogDamage {
  std::string path;               ///< the rawlog
  std::size_t object_index = 0;   ///< 0-based index of the first top-level object not read
  std::uint64_t byte_offset = 0;  ///< where it starts [bytes of the decompressed stream]
  std::string reason;             ///< why it could not be read
  std::size_t observations_before = 0;  ///< observations read intact before it
};

RawlogDamage damageOf(const mrpt_bridge::RawlogError& err, std::size_t observations_before);

/// summary.json's "damage": {"object_index", "byte_offset", "byte_offset_in", "reason",
/// "observations_before"}.
nlohmann::json damageJson(const RawlogDamage& damage);

/// The one line printed on stderr: the file, the object index, the offset, the reason and
/// where the maps of the good frames went.
std::string damageLine(const RawlogDamage& damage, const std::string& out_dir);

}  // namespace upd::app
