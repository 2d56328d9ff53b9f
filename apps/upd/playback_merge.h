// Several rawlogs in one `upd playback`: runs of the same site, each with its own poses,
// fused one after the other into the same grid and tree (one map of every run).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace upd::app {

/// One rawlog of the command line and the TUM poses it is played with (none: its odometry).
struct PlaybackRun {
  std::string rawlog;
  std::optional<std::string> poses_path;
};

/// The runs of `upd playback RAWLOG... [--poses A.tum[,B.tum...]]`: --poses names one file per
/// rawlog, in order. Throws UsageError when the counts differ, or when per_frame_outputs
/// (--ply, --output-rawlog: files named by frame index) is asked for with several rawlogs.
std::vector<PlaybackRun> playbackRuns(const std::vector<std::string>& rawlogs,
                                      const std::optional<std::string>& poses,
                                      bool per_frame_outputs);

}  // namespace upd::app
