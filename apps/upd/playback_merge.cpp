#include "playback_merge.h"

#include "cli.h"

#include <sstream>

namespace upd::app {

std::vector<PlaybackRun> playbackRuns(const std::vector<std::string>& rawlogs,
                                      const std::optional<std::string>& poses,
                                      bool per_frame_outputs) {
  if (rawlogs.empty()) throw UsageError("expected at least one RAWLOG");
  if (rawlogs.size() > 1 && per_frame_outputs) {
    throw UsageError("--ply and --output-rawlog take one RAWLOG (" +
                     std::to_string(rawlogs.size()) + " given)");
  }
  std::vector<std::string> pose_files;
  if (poses) {
    std::istringstream in(*poses);
    for (std::string f; std::getline(in, f, ',');) pose_files.push_back(f);
    if (pose_files.size() != rawlogs.size()) {
      throw UsageError("option --poses = " + *poses + ": " + std::to_string(pose_files.size()) +
                       " file(s) for " + std::to_string(rawlogs.size()) +
                       " rawlog(s) (one per rawlog, comma-separated)");
    }
  }
  std::vector<PlaybackRun> runs;
  for (std::size_t k = 0; k < rawlogs.size(); ++k) {
    runs.push_back({rawlogs[k], poses ? std::optional<std::string>(pose_files[k]) : std::nullopt});
  }
  return runs;
}

}  // namespace upd::app
