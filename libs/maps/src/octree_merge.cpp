// Merging and cropping the traversability OctoMap tree (map_merge.h).
#include "upd/maps/map_merge.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace upd::maps {

namespace {

// into's traversability += from's (the rule of map_merge.h).
void mergeTraversability(TraversabilityOcTreeNode& into, const TraversabilityOcTreeNode& from,
                         const FusionParams& fusion) {
  if (!from.hasTraversability()) return;
  if (!into.hasTraversability()) {
    into.setTraversability(from.getTraversabilityLogOdds(), from.getZetaMin(), from.getCostMean(),
                           from.getObservations());
    return;
  }
  const float la = into.getTraversabilityLogOdds(), lb = from.getTraversabilityLogOdds();
  const float logodds = fuseLogOdds(0.f, (std::isnan(la) ? 0.0 : la) + (std::isnan(lb) ? 0.0 : lb),
                                    fusion);
  const unsigned na = into.getObservations(), nb = from.getObservations();
  const float ca = into.getCostMean(), cb = from.getCostMean();
  float cost = std::isnan(ca) ? cb : ca;
  if (!std::isnan(ca) && !std::isnan(cb)) {
    cost = static_cast<float>((static_cast<double>(ca) * na + static_cast<double>(cb) * nb) /
                              std::max(1.0, static_cast<double>(na) + nb));
  }
  const auto obs = static_cast<std::uint16_t>(
      std::min<unsigned>(na + nb, std::numeric_limits<std::uint16_t>::max()));
  into.setTraversability(logodds, std::fmin(into.getZetaMin(), from.getZetaMin()), cost, obs);
}

}  // namespace

void mergeOctreeInto(TraversabilityOcTree& into, const TraversabilityOcTree& from,
                     const FusionParams& fusion) {
  if (std::abs(into.getResolution() - from.getResolution()) > 1e-9 * into.getResolution()) {
    throw std::invalid_argument("mergeOctreeInto: voxel sizes differ (" +
                                std::to_string(into.getResolution()) + " m and " +
                                std::to_string(from.getResolution()) + " m)");
  }
  const unsigned tree_depth = from.getTreeDepth();
  for (auto it = from.begin_leafs(), end = from.end_leafs(); it != end; ++it) {
    // A pruned leaf stands for every voxel of its cube, from its lower corner key.
    const unsigned span = 1u << (tree_depth - it.getDepth());
    const octomap::OcTreeKey k0 = it.getIndexKey();
    for (unsigned dx = 0; dx < span; ++dx) {
      for (unsigned dy = 0; dy < span; ++dy) {
        for (unsigned dz = 0; dz < span; ++dz) {
          const octomap::OcTreeKey k(static_cast<octomap::key_type>(k0[0] + dx),
                                     static_cast<octomap::key_type>(k0[1] + dy),
                                     static_cast<octomap::key_type>(k0[2] + dz));
          TraversabilityOcTreeNode* n = into.updateNode(k, it->getLogOdds(), true);
          if (n != nullptr) mergeTraversability(*n, *it, fusion);
        }
      }
    }
  }
  into.updateInnerOccupancy();
}

void cropOctree(TraversabilityOcTree& tree, const Region& r) {
  auto key = [&](double v) {
    const double k = std::floor(v / tree.getResolution()) + tree.coordToKey(0.0);
    return static_cast<octomap::key_type>(
        std::clamp(k, 0.0, static_cast<double>(std::numeric_limits<octomap::key_type>::max())));
  };
  // [x_min, x_max): the last key is the one just below x_max.
  const double eps = 1e-9 * tree.getResolution();
  const octomap::OcTreeKey lo(key(r.x_min), key(r.y_min), 0);
  const octomap::OcTreeKey hi(key(r.x_max - eps), key(r.y_max - eps),
                              std::numeric_limits<octomap::key_type>::max());
  tree.cropToKeyBox(lo, hi);
}

}  // namespace upd::maps
