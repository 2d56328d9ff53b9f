#include "playback_damage.h"

#include <sstream>

namespace upd::app {

RawlogDamage damageOf(const mrpt_bridge::RawlogError& err, std::size_t observations_before) {
  RawlogDamage d;
  d.path = err.path();
  d.object_index = err.objectIndex();
  d.byte_offset = err.byteOffset();
  d.reason = err.reason().empty() ? std::string(err.what()) : err.reason();
  d.observations_before = observations_before;
  return d;
}

nlohmann::json damageJson(const RawlogDamage& damage) {
  return {{"object_index", damage.object_index},
          {"byte_offset", damage.byte_offset},
          {"byte_offset_in", "decompressed stream"},
          {"reason", damage.reason},
          {"observations_before", damage.observations_before}};
}

std::string damageLine(const RawlogDamage& damage, const std::string& out_dir) {
  std::ostringstream os;
  os << "upd playback: warning: rawlog " << damage.path << " is damaged at object #"
     << damage.object_index << " (byte " << damage.byte_offset
     << " of the decompressed stream): " << damage.reason << "; maps of the "
     << damage.observations_before << " observations before it written to " << out_dir
     << " (partial, exit " << kExitPartial << ")";
  return os.str();
}

}  // namespace upd::app
