// The viewer of `upd playback --view` (playback_view.h).
#include "playback_view.h"

#include <cstdio>

namespace upd::app {

namespace {

nav::ViewerOptions playbackViewOptions(const std::string& rawlog) {
  nav::ViewerOptions o;
  o.title = "upd playback " + rawlog;
  o.follow_robot = true;
  return o;
}

}  // namespace

PlaybackView::PlaybackView(const std::string& rawlog) : viewer_(playbackViewOptions(rawlog)) {}

void PlaybackView::show(const core::ScoredFrame& frame, const maps::TraversabilityGrid& grid,
                        const maps::TraversabilityOcTree& tree, const std::vector<Eigen::Vector3d>& trajectory) {
  if (!viewer_.processEvents()) return;
  nav::MapSnapshot map;
  nav::snapshotGrid(grid, map);
  // The voxels only while they are shown: the tree of a long run has many.
  if (viewer_.mapStyle() == nav::MapStyle::Octree) nav::snapshotOctree(tree, map, grid.params().p_nontrav_threshold);
  for (const auto& p : trajectory) map.path.push_back(p.cast<float>());
  viewer_.setContent(nav::scoredCloudOf(frame), std::move(map));
}

void PlaybackView::waitUntilClosed() {
  if (!viewer_.isOpen()) return;
  std::printf("upd playback: done; close the viewer's window (or press q) to exit\n");
  std::fflush(stdout);
  viewer_.runUntilClosed();
}

}  // namespace upd::app
