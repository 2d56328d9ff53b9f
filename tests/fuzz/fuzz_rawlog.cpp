// A rawlog object stream on arbitrary bytes (plain; a gzip header is inflated as MRPT does):
// every object is read and every observation converted to a cloud as `upd playback` does.
// Any input must end cleanly or in a RawlogError / std::exception.
#include "fuzz_input.h"

#include "upd/mrpt_bridge/observation_cloud.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/obs/CObservation.h>

#include <algorithm>
#include <stdexcept>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // MRPT 2.5.8 deserializes CObservationVelodyneScan's calibration by resizing a vector to the
  // count it reads: a corrupt count allocates what it says. A normal build gets std::bad_alloc
  // for an impossible size, which the reader reports as damage (PlaybackDamage.
  // AnObjectClaimingAnImpossibleSizeIsDamageNotACrash); ASan's operator new aborts instead.
  // That class (in plain streams) is left out; docs/RELIABILITY.md, "Fuzzing".
  constexpr std::string_view kVelodyne = "CObservationVelodyneScan";
  if (std::search(data, data + size, kVelodyne.begin(), kVelodyne.end()) != data + size) return -1;
  static const std::string path = upd::fuzz::inputPath(".rawlog");
  upd::fuzz::writeInput(path, data, size);
  try {
    upd::mrpt_bridge::RawlogReader reader(path);
    upd::mrpt_bridge::RawlogEntry entry;
    upd::mrpt_bridge::ObservationCloud cloud;
    for (int n = 0; n < 64 && reader.next(entry); ++n) {
      upd::mrpt_bridge::toCloud(*entry.observation, {}, cloud);
    }
  } catch (const std::exception&) {
    // damage: what the reader reports
  }
  return 0;
}
