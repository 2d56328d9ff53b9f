// A rawlog object stream on arbitrary bytes (plain; a gzip header is inflated as MRPT does):
// every object is read and every observation converted to a cloud as `upd playback` does.
// Any input must end cleanly or in a RawlogError / std::exception.
#include "fuzz_input.h"

#include "upd/mrpt_bridge/observation_cloud.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/obs/CObservation.h>

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
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
