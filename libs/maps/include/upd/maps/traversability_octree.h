// The 3D traversability map: an OctoMap tree whose voxels store traversability beside occupancy.
//
// OctoMap is extended the way its ColorOcTree is: a node type (TraversabilityOcTreeNode :
// OcTreeNode) that adds the fused traversability of the points that ended in the voxel, and a tree
// (TraversabilityOcTree) registered with OctoMap's tree factory, so AbstractOcTree::read() of a
// .ot file written here returns a TraversabilityOcTree (in any program linking upd_maps).
//
// Occupancy is OctoMap's own ray-casting log-odds update (free along each ray, occupied at its
// end point). Traversability follows the same per-frame rule as the grid (fusion.h): the frame's
// labelled points are aggregated per voxel and each end-point voxel gets one log-odds update per
// frame. An inner node holds its WORST child: the highest non-traversable log-odds, the lowest
// zeta_min, the highest cost and the most observations (and, as in OctoMap, the highest
// occupancy), so a coarse query never hides an obstacle.
//
// Insertion is batched: the occupancy of OctoMap's insertPointCloud with lazy evaluation (the
// same free and occupied voxels, each updated once), the traversability of the hit voxels, then
// one update of the inner nodes above the voxels the frame changed.
//
// Bounded memory: updates are limited to a box (OctoMap's BBX limit). With follow_robot the box
// (extent_m x extent_m x height_m) is re-centred on the sensor whenever the sensor gets farther
// than recenter_fraction of the box size from its centre along any axis; without it the box is
// fixed around center_*_m. With keep_outside_box (the default) every subtree that leaves the box
// is kept, as compressed leaf records in tiles of tile_voxels x tile_voxels voxels (x, y; every
// z), and put back into the tree when the box returns over its tile, so a revisited area
// continues fusing onto its old evidence; wholeRun() is the whole run as one tree. Memory is the
// tree inside the box plus the kept tiles (keptTileBytes(), measured in docs/MAPS.md). Without
// it every node outside the new box is deleted.
//
// Files: writeTraversabilityOt holds everything (occupancy and traversability) and reloads
// with readTraversabilityOt, or octomap::AbstractOcTree::read in programs that link this
// library (which registers the type); no OctoMap tool knows the type. For those tools,
// writeColourOt() writes a standard ColorOcTree .ot coloured by traversability (what `upd
// playback` calls map.ot: convert_octree, octovis and AbstractOcTree::read open it), and
// writeOccupancyBt() a plain OcTree .bt with occupancy only.
#pragma once

#include "upd/maps/fusion.h"

#include <Eigen/Core>
#include <octomap/OcTreeNode.h>
#include <octomap/OccupancyOcTreeBase.h>  // brings OcTreeKey.h, which needs <cstdint> first

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace octomap {
class ColorOcTree;
}

namespace upd::maps {

class TraversabilityOcTree;
namespace detail {
class OctreeTileStore;  // octree_tiles.h: the kept subtrees
}

class TraversabilityOcTreeNode : public octomap::OcTreeNode {
 public:
  friend class TraversabilityOcTree;  // needs the node's children for cropping

  TraversabilityOcTreeNode() = default;
  TraversabilityOcTreeNode(const TraversabilityOcTreeNode& rhs);

  /// Equal occupancy and traversability (NaN equals NaN): the test OctoMap uses for pruning.
  bool operator==(const TraversabilityOcTreeNode& rhs) const;
  void copyData(const TraversabilityOcTreeNode& from);

  /// Log-odds of non-traversable; NaN when no labelled point ever ended in the voxel.
  float getTraversabilityLogOdds() const { return trav_logodds_; }
  /// Probability of non-traversable; NaN when never observed.
  float getNonTraversableProbability() const { return probabilityFromLogOdds(trav_logodds_); }
  float getZetaMin() const { return zeta_min_; }    ///< NaN when never scored
  float getCostMean() const { return cost_mean_; }  ///< NaN when never scored
  /// Frames that updated the traversability (saturates at 65535).
  std::uint16_t getObservations() const { return observations_; }
  bool hasTraversability() const { return observations_ > 0; }

  void setTraversability(float logodds, float zeta_min, float cost_mean,
                         std::uint16_t observations);
  /// Sets this (inner) node's traversability to its worst child's.
  void updateTraversabilityChildren();

  // File I/O (the .ot format): occupancy log-odds then the traversability fields.
  std::istream& readData(std::istream& s);
  std::ostream& writeData(std::ostream& s) const;

 protected:
  float trav_logodds_ = std::numeric_limits<float>::quiet_NaN();
  float zeta_min_ = std::numeric_limits<float>::quiet_NaN();
  float cost_mean_ = std::numeric_limits<float>::quiet_NaN();
  std::uint16_t observations_ = 0;
};

/// The octree map's parameters. Loaded from [OctreeParams].
struct OctreeParams {
  double resolution_m = 0.1;  ///< voxel side [m]
  /// Points farther than this from the sensor are ignored (in OctoMap's box-limited update a
  /// too-long ray clears no free space either); <= 0: no limit [m].
  double max_range_m = 10.0;
  double prob_hit = 0.7;           ///< OctoMap occupancy update of a ray's end voxel
  double prob_miss = 0.4;          ///< OctoMap occupancy update of the voxels a ray crosses
  double prob_clamp_min = 0.1192;  ///< OctoMap's default clamping (log-odds -2)
  double prob_clamp_max = 0.971;   ///< OctoMap's default clamping (log-odds 3.5)
  /// true: one ray per end voxel, cast from its centre (OctoMap's discretized insert: the
  /// same occupied voxels, free space carved from voxel centres; a 640 x 480 frame at 0.1 m
  /// casts a few thousand rays instead of 300,000). false: one ray per point.
  bool discretize = true;
  bool follow_robot = true;        ///< true: the update box follows the sensor; false: fixed box
  double extent_m = 40.0;          ///< side of the update box along x and y [m]
  double height_m = 10.0;          ///< size of the update box along z [m]
  double center_x_m = 0.0;         ///< box centre [m, world]: fixed, or until the first scan
  double center_y_m = 0.0;
  double center_z_m = 0.0;
  /// The box is re-centred when the sensor is farther than this fraction of the box size from
  /// its centre along an axis (0..0.5).
  double recenter_fraction = 0.25;
  /// true: subtrees leaving the box are kept (compressed tiles) and come back when the box
  /// returns; false: they are deleted.
  bool keep_outside_box = true;
  int tile_voxels = 128;  ///< side of a kept tile along x and y [voxels]; a power of two

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("resolution_m", resolution_m, "voxel side [m]");
    v("max_range_m", max_range_m, "points farther from the sensor are ignored [m]; <= 0: none");
    v("prob_hit", prob_hit, "OctoMap occupancy probability of a ray's end voxel (0.5..1)");
    v("prob_miss", prob_miss, "OctoMap occupancy probability of a crossed voxel (0..0.5)");
    v("prob_clamp_min", prob_clamp_min, "lower occupancy clamp (0..0.5)");
    v("prob_clamp_max", prob_clamp_max, "upper occupancy clamp (0.5..1)");
    v("discretize", discretize,
      "true: one ray per end voxel (OctoMap's discretized insert, much faster); false: one "
      "ray per point");
    v("follow_robot", follow_robot, "true: the update box follows the sensor; false: fixed");
    v("extent_m", extent_m, "side of the update box along x and y [m] (memory bound)");
    v("height_m", height_m, "size of the update box along z [m] (memory bound)");
    v("center_x_m", center_x_m, "box centre x [m, world] (fixed, or initial)");
    v("center_y_m", center_y_m, "box centre y [m, world] (fixed, or initial)");
    v("center_z_m", center_z_m, "box centre z [m, world] (fixed, or initial)");
    v("recenter_fraction", recenter_fraction,
      "re-centre when the sensor is this fraction of the box size from its centre (0..0.5)");
    v("keep_outside_box", keep_outside_box,
      "true: subtrees leaving the box are kept in compressed tiles and restored on return "
      "(whole-run maps); false: deleted");
    v("tile_voxels", tile_voxels, "side of a kept tile along x and y [voxels] (power of two, 8..4096)");
  }
};

class TraversabilityOcTree : public octomap::OccupancyOcTreeBase<TraversabilityOcTreeNode> {
 public:
  /// OctoMap's default occupancy probabilities; the constructor the tree factory uses.
  explicit TraversabilityOcTree(double resolution_m);
  /// Resolution and occupancy probabilities from params (validated).
  explicit TraversabilityOcTree(const OctreeParams& params);
  ~TraversabilityOcTree() override;
  TraversabilityOcTree(const TraversabilityOcTree&) = delete;  // OctoMap's copy slices nodes
  TraversabilityOcTree& operator=(const TraversabilityOcTree&) = delete;

  TraversabilityOcTree* create() const override { return new TraversabilityOcTree(resolution); }
  std::string getTreeType() const override { return "TraversabilityOcTree"; }

  /// One frame's traversability evidence for the voxel at key (which must exist, e.g. after
  /// an occupancy update): n_nontrav / n_trav labelled points ended there, with this minimum
  /// zeta and mean cost (NaN: none). Leaves inner nodes stale (call updateInnerOccupancy()).
  /// Returns the node, or nullptr when the voxel does not exist or the counts give no update.
  TraversabilityOcTreeNode* integrateTraversability(const octomap::OcTreeKey& key,
                                                    std::size_t n_nontrav, std::size_t n_trav,
                                                    float zeta_min, float cost_mean,
                                                    const FusionParams& params);

  /// OctoMap's updateNode(key, false / true, lazy_eval = true) for each of the free and
  /// occupied keys (distinct; none in both), in one descent of the tree in Morton order: the
  /// same tree as the calls one after the other, in any order (inner nodes left stale).
  void updateNodes(const std::vector<octomap::OcTreeKey>& free,
                   const std::vector<octomap::OcTreeKey>& occupied);

  /// Updates inner nodes' occupancy (max child) and traversability (worst child).
  void updateInnerOccupancy();
  /// The same for the inner nodes above the voxels at changed only (the others must be up to
  /// date): what a frame's updates need, at a cost that does not grow with the tree.
  void updateInnerOccupancy(const std::vector<octomap::OcTreeKey>& changed);

  /// Deletes every node that lies entirely outside the box (OcTreeKey bounds, inclusive),
  /// expanding pruned nodes that straddle it, then refreshes the inner nodes.
  void cropToKeyBox(const octomap::OcTreeKey& min_key, const octomap::OcTreeKey& max_key);
  /// cropToKeyBox, but what lies outside the box is kept in tiles of tile_voxels (a power of
  /// two) along x and y instead of deleted. Throws std::invalid_argument when tile_voxels
  /// differs from the tiles kept so far.
  void cropToKeyBoxKeeping(const octomap::OcTreeKey& min_key, const octomap::OcTreeKey& max_key,
                           int tile_voxels);
  /// Puts every kept tile that overlaps the box (along x and y) back into the tree.
  void restoreKeptTiles(const octomap::OcTreeKey& min_key, const octomap::OcTreeKey& max_key);
  std::size_t keptTiles() const;      ///< tiles kept from outside the box
  std::size_t keptLeaves() const;     ///< leaves in them
  std::size_t keptTileBytes() const;  ///< their compressed bytes plus a per-tile allowance
  /// The tree and every kept subtree as one tree (inner nodes updated), for the exports.
  std::unique_ptr<TraversabilityOcTree> wholeRun() const;
  /// The same in place: every kept tile is put back into this tree (which then holds the
  /// whole run, and its memory).
  void mergeKeptTiles();

 protected:
  void updateInnerOccupancyRecurs(TraversabilityOcTreeNode* node, unsigned int depth);
  /// The nodes above the keys of Morton codes [lo, hi) (sorted) below node.
  void updateInnerOccupancyRecurs(TraversabilityOcTreeNode* node, unsigned int depth,
                                  const std::uint64_t* lo, const std::uint64_t* hi);
  /// updateNodes below node (on the path of every key of the codes [lo, hi), sorted; created
  /// by this descent when just_created); may reorder the codes.
  void updateNodesRecurs(TraversabilityOcTreeNode* node, bool just_created, unsigned int depth,
                         std::uint64_t* lo, std::uint64_t* hi);
  /// Returns true when the caller should delete node (nothing of it is inside the box).
  /// keep: where the deleted subtrees go (nullptr: nowhere).
  bool cropRecurs(TraversabilityOcTreeNode* node, const octomap::OcTreeKey& key, unsigned int depth,
                  const octomap::OcTreeKey& min_key, const octomap::OcTreeKey& max_key,
                  detail::OctreeTileStore* keep = nullptr);
  /// Adds the leaves of node's subtree to keep, splitting nodes larger than a tile.
  void keepSubtree(TraversabilityOcTreeNode* node, const octomap::OcTreeKey& key,
                   unsigned int depth, detail::OctreeTileStore& keep);
  /// Sets the node at (key, depth) to data, creating the nodes on the way.
  void setNodeAt(const octomap::OcTreeKey& key, unsigned int depth,
                 const TraversabilityOcTreeNode& data);
  /// Calls f(key, depth, node) for every leaf below node.
  template <class F>
  void forEachLeaf(const TraversabilityOcTreeNode* node, const octomap::OcTreeKey& key,
                   unsigned int depth, F&& f) const;

  /// Registers the tree type with OctoMap's factory once (ColorOcTree's pattern).
  class StaticMemberInitializer {
   public:
    StaticMemberInitializer();
    void ensureLinking() {}
  };
  static StaticMemberInitializer traversability_octree_member_init_;

 private:
  std::unique_ptr<detail::OctreeTileStore> kept_;
};

/// What one insertScan() call did.
struct OctreeInsertStats {
  std::size_t points_inserted = 0;        ///< finite points ray-cast (all labels)
  std::size_t points_invalid = 0;         ///< non-finite coordinates: ignored
  std::size_t points_unknown = 0;         ///< finite but Unknown: occupancy only
  std::size_t voxels_traversability = 0;  ///< voxels whose traversability was updated
  bool window_moved = false;
};

/// Inserts one frame: occupancy by ray casting from sensor_origin_world (OctoMap's batch update
/// with lazy evaluation, limited to the update box and to max_range_m), then the traversability
/// of the end-point voxels, then the inner nodes above the voxels it changed. Moves and crops
/// the box first when follow_robot. Throws std::invalid_argument for bad parameters, an invalid view, or
/// params.resolution_m different from the tree's.
OctreeInsertStats insertScan(TraversabilityOcTree& tree, const PointsWorld& points,
                             const Eigen::Vector3d& sensor_origin_world, const OctreeParams& params,
                             const FusionParams& fusion);

struct OctreeStats {
  std::size_t nodes = 0;
  std::size_t leaves = 0;
  std::size_t occupied_leaves = 0;
  std::size_t traversability_leaves = 0;   ///< leaves with traversability evidence
  std::size_t non_traversable_leaves = 0;  ///< ... with probability >= 0.5
  std::size_t memory_bytes = 0;            ///< OctoMap's memoryUsage()
};
OctreeStats computeStats(const TraversabilityOcTree& tree);

/// The full tree (occupancy + traversability) as a .ot file.
void writeTraversabilityOt(const TraversabilityOcTree& tree, const std::string& path);
/// Occupancy only, as a binary OcTree .bt (maximum likelihood, id OcTree), for any OctoMap tool.
void writeOccupancyBt(const TraversabilityOcTree& tree, const std::string& path);
/// A ColorOcTree .ot with the same structure and occupancy, coloured as the grid PNG (green
/// traversable -> red non-traversable, grey without evidence): what octovis can show.
void writeColourOt(const TraversabilityOcTree& tree, const std::string& path);
/// An .ot file's header: the tree type (OctoMap's id line), the resolution and the node count.
struct OtHeader {
  std::string id;
  double resolution = 0;
  std::size_t nodes = 0;
};
/// Reads the header of an .ot file (without reading its nodes, and without OctoMap's messages
/// on stderr). Throws std::runtime_error naming the file when it is not an OctoMap .ot.
OtHeader readOtHeader(const std::string& path);
/// Reads a .ot written by writeTraversabilityOt. Throws std::runtime_error naming the file when
/// it cannot be read, holds another tree type, or ends before the header's number of nodes.
std::unique_ptr<TraversabilityOcTree> readTraversabilityOt(const std::string& path);
/// Reads a ColorOcTree .ot (writeColourOt's map.ot, or another OctoMap tool's), with the same
/// checks as readTraversabilityOt.
std::unique_ptr<octomap::ColorOcTree> readColourOt(const std::string& path);
/// Either tree UPD-Nav writes as .ot; exactly one member is set.
struct AnyOt {
  std::unique_ptr<TraversabilityOcTree> traversability;
  std::unique_ptr<octomap::ColorOcTree> colour;
};
/// Reads a TraversabilityOcTree or a ColorOcTree .ot, whichever the header names, opening the
/// file once, with the same checks as readTraversabilityOt; another tree type is an error.
AnyOt readAnyOt(const std::string& path);

}  // namespace upd::maps
