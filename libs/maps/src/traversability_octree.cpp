#include "upd/maps/traversability_octree.h"

#include "upd/io/atomic_file.h"
#include "upd/maps/grid_export.h"

#include "key_sets.h"
#include "octree_tiles.h"

#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace upd::maps {

namespace {

bool sameFloat(float a, float b) { return a == b || (std::isnan(a) && std::isnan(b)); }

// Larger of two log-odds / costs where NaN means "no evidence".
float maxEvidence(float a, float b) {
  if (std::isnan(a)) return b;
  if (std::isnan(b)) return a;
  return std::max(a, b);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Node

TraversabilityOcTreeNode::TraversabilityOcTreeNode(const TraversabilityOcTreeNode& rhs)
    : OcTreeNode(rhs),
      trav_logodds_(rhs.trav_logodds_),
      zeta_min_(rhs.zeta_min_),
      cost_mean_(rhs.cost_mean_),
      observations_(rhs.observations_) {}

bool TraversabilityOcTreeNode::operator==(const TraversabilityOcTreeNode& rhs) const {
  return rhs.value == value && sameFloat(rhs.trav_logodds_, trav_logodds_) &&
         sameFloat(rhs.zeta_min_, zeta_min_) && sameFloat(rhs.cost_mean_, cost_mean_) &&
         rhs.observations_ == observations_;
}

void TraversabilityOcTreeNode::copyData(const TraversabilityOcTreeNode& from) {
  OcTreeNode::copyData(from);
  trav_logodds_ = from.trav_logodds_;
  zeta_min_ = from.zeta_min_;
  cost_mean_ = from.cost_mean_;
  observations_ = from.observations_;
}

void TraversabilityOcTreeNode::setTraversability(float logodds, float zeta_min, float cost_mean,
                                                 std::uint16_t observations) {
  trav_logodds_ = logodds;
  zeta_min_ = zeta_min;
  cost_mean_ = cost_mean;
  observations_ = observations;
}

void TraversabilityOcTreeNode::updateTraversabilityChildren() {
  if (children == nullptr) return;
  float logodds = std::numeric_limits<float>::quiet_NaN();
  float zeta_min = std::numeric_limits<float>::quiet_NaN();
  float cost = std::numeric_limits<float>::quiet_NaN();
  std::uint16_t observations = 0;
  for (int i = 0; i < 8; ++i) {
    const auto* c = static_cast<const TraversabilityOcTreeNode*>(children[i]);
    if (c == nullptr) continue;
    logodds = maxEvidence(logodds, c->trav_logodds_);
    zeta_min = std::fmin(zeta_min, c->zeta_min_);
    cost = maxEvidence(cost, c->cost_mean_);
    observations = std::max(observations, c->observations_);
  }
  setTraversability(logodds, zeta_min, cost, observations);
}

std::ostream& TraversabilityOcTreeNode::writeData(std::ostream& s) const {
  s.write(reinterpret_cast<const char*>(&value), sizeof(value));
  s.write(reinterpret_cast<const char*>(&trav_logodds_), sizeof(trav_logodds_));
  s.write(reinterpret_cast<const char*>(&zeta_min_), sizeof(zeta_min_));
  s.write(reinterpret_cast<const char*>(&cost_mean_), sizeof(cost_mean_));
  s.write(reinterpret_cast<const char*>(&observations_), sizeof(observations_));
  return s;
}

std::istream& TraversabilityOcTreeNode::readData(std::istream& s) {
  // A failed stream (the data ended early) stops the read here: OctoMap's readNodesRecurs goes
  // on with the child bits it could not read, uninitialized, and would build nodes from them
  // (an exponential number, whatever the stack held).
  if (!s) throw std::ios_base::failure("the octree's data ends before its last node");
  s.read(reinterpret_cast<char*>(&value), sizeof(value));
  s.read(reinterpret_cast<char*>(&trav_logodds_), sizeof(trav_logodds_));
  s.read(reinterpret_cast<char*>(&zeta_min_), sizeof(zeta_min_));
  s.read(reinterpret_cast<char*>(&cost_mean_), sizeof(cost_mean_));
  s.read(reinterpret_cast<char*>(&observations_), sizeof(observations_));
  return s;
}

// ---------------------------------------------------------------------------------------------
// Parameters

void OctreeParams::validate() const {
  core::requireParam(std::isfinite(resolution_m) && resolution_m > 0, "OctreeParams", "resolution_m",
               resolution_m, "must be > 0");
  core::requireParam(std::isfinite(max_range_m), "OctreeParams", "max_range_m", max_range_m,
               "must be finite (<= 0 for no limit)");
  core::requireParam(prob_hit > 0.5 && prob_hit < 1, "OctreeParams", "prob_hit", prob_hit,
               "must be in (0.5, 1)");
  core::requireParam(prob_miss > 0 && prob_miss < 0.5, "OctreeParams", "prob_miss", prob_miss,
               "must be in (0, 0.5)");
  core::requireParam(prob_clamp_min > 0 && prob_clamp_min < 0.5, "OctreeParams", "prob_clamp_min",
               prob_clamp_min, "must be in (0, 0.5)");
  core::requireParam(prob_clamp_max > 0.5 && prob_clamp_max < 1, "OctreeParams", "prob_clamp_max",
               prob_clamp_max, "must be in (0.5, 1)");
  core::requireParam(std::isfinite(extent_m) && extent_m >= 2 * resolution_m, "OctreeParams", "extent_m",
               extent_m, "must be at least two voxels");
  core::requireParam(std::isfinite(height_m) && height_m >= 2 * resolution_m, "OctreeParams", "height_m",
               height_m, "must be at least two voxels");
  core::requireParam(std::isfinite(center_x_m), "OctreeParams", "center_x_m", center_x_m,
               "must be finite");
  core::requireParam(std::isfinite(center_y_m), "OctreeParams", "center_y_m", center_y_m,
               "must be finite");
  core::requireParam(std::isfinite(center_z_m), "OctreeParams", "center_z_m", center_z_m,
               "must be finite");
  core::requireParam(recenter_fraction > 0 && recenter_fraction < 0.5, "OctreeParams",
               "recenter_fraction", recenter_fraction, "must be in (0, 0.5)");
  core::requireParam(tile_voxels >= 8 && tile_voxels <= 4096 && (tile_voxels & (tile_voxels - 1)) == 0,
                     "OctreeParams", "tile_voxels", tile_voxels, "must be a power of two in [8, 4096]");
}

// ---------------------------------------------------------------------------------------------
// Tree

TraversabilityOcTree::StaticMemberInitializer
    TraversabilityOcTree::traversability_octree_member_init_;

TraversabilityOcTree::StaticMemberInitializer::StaticMemberInitializer() {
  // The factory keeps this prototype for the life of the process (OctoMap's pattern).
  auto* tree = new TraversabilityOcTree(0.1);
  tree->clearKeyRays();
  octomap::AbstractOcTree::registerTreeType(tree);
}

TraversabilityOcTree::TraversabilityOcTree(double resolution_m)
    : octomap::OccupancyOcTreeBase<TraversabilityOcTreeNode>(resolution_m) {
  traversability_octree_member_init_.ensureLinking();
}

TraversabilityOcTree::TraversabilityOcTree(const OctreeParams& params)
    : TraversabilityOcTree((params.validate(), params.resolution_m)) {
  setProbHit(params.prob_hit);
  setProbMiss(params.prob_miss);
  setClampingThresMin(params.prob_clamp_min);
  setClampingThresMax(params.prob_clamp_max);
}

TraversabilityOcTreeNode* TraversabilityOcTree::integrateTraversability(
    const octomap::OcTreeKey& key, std::size_t n_nontrav, std::size_t n_trav, float zeta_min,
    float cost_mean, const FusionParams& params) {
  const double update = frameLogOddsUpdate(n_nontrav, n_trav, params);
  if (update == 0.0) return nullptr;
  TraversabilityOcTreeNode* n = search(key);
  if (n == nullptr) return nullptr;
  const float logodds = fuseLogOdds(n->trav_logodds_, update, params);
  float cost = n->cost_mean_;
  if (!std::isnan(cost_mean)) {
    // Running mean over the frames that scored the voxel (each frame counts once).
    cost = std::isnan(cost) ? cost_mean
                            : (cost * n->observations_ + cost_mean) / (n->observations_ + 1.0f);
  }
  const auto observations = static_cast<std::uint16_t>(
      std::min<unsigned>(n->observations_ + 1u, std::numeric_limits<std::uint16_t>::max()));
  n->setTraversability(logodds, std::fmin(n->zeta_min_, zeta_min), cost, observations);
  return n;
}

void TraversabilityOcTree::updateInnerOccupancy() {
  if (root != nullptr) updateInnerOccupancyRecurs(root, 0);
}

void TraversabilityOcTree::updateInnerOccupancyRecurs(TraversabilityOcTreeNode* node,
                                                      unsigned int depth) {
  if (!nodeHasChildren(node)) return;
  if (depth < tree_depth) {
    for (unsigned int i = 0; i < 8; ++i) {
      if (nodeChildExists(node, i)) updateInnerOccupancyRecurs(getNodeChild(node, i), depth + 1);
    }
  }
  node->updateOccupancyChildren();
  node->updateTraversabilityChildren();
}

namespace {

// The key's Morton code: from the root down, each level's child index (OctoMap's
// computeChildIdx: x bit 1, y bit 2, z bit 4) in 3 bits, the root's child the highest.
std::uint64_t mortonOf(const octomap::OcTreeKey& k) {
  const auto spread = [](std::uint64_t v) {  // bit i to bit 3 i
    v = (v | v << 16) & 0x0000FF0000FFull;
    v = (v | v << 8) & 0x00F00F00F00Full;
    v = (v | v << 4) & 0x0C30C30C30C3ull;
    return (v | v << 2) & 0x249249249249ull;
  };
  return spread(k[0]) | spread(k[1]) << 1 | spread(k[2]) << 2;
}

// Calls f(child, a, b) for each run [a, b) of the sorted codes [lo, hi) under one child of a
// node, the child's index the 3 bits at shift: the codes under one child are consecutive
// (sorted, its index their highest bits left).
template <class Code, class F>
void forEachChildRun(Code* lo, Code* hi, unsigned int shift, F&& f) {
  for (Code* a = lo; a < hi;) {
    const auto child = static_cast<unsigned int>((*a >> shift) & 7);
    Code* b = a + 1;
    while (b < hi && ((*b >> shift) & 7) == child) ++b;
    f(child, a, b);
    a = b;
  }
}

}  // namespace

void TraversabilityOcTree::updateInnerOccupancy(const std::vector<octomap::OcTreeKey>& changed) {
  if (root == nullptr || changed.empty()) return;
  std::vector<std::uint64_t> codes(changed.size()), buffer;
  for (std::size_t i = 0; i < changed.size(); ++i) codes[i] = mortonOf(changed[i]);
  detail::radixSort(codes, buffer, 48);  // (the order only spares visits: any order updates all)
  codes.erase(std::unique(codes.begin(), codes.end()), codes.end());
  updateInnerOccupancyRecurs(root, 0, codes.data(), codes.data() + codes.size());
}

void TraversabilityOcTree::updateNodes(const std::vector<octomap::OcTreeKey>& free,
                                       const std::vector<octomap::OcTreeKey>& occupied) {
  // The keys in Morton order, each code's lowest bit whether it is occupied.
  std::vector<std::uint64_t> codes, buffer;
  codes.reserve(free.size() + occupied.size());
  for (const auto& k : free) codes.push_back(mortonOf(k) << 1);
  for (const auto& k : occupied) codes.push_back(mortonOf(k) << 1 | 1);
  if (codes.empty()) return;
  detail::radixSort(codes, buffer, 49);
  bool created = false;
  if (root == nullptr) {
    root = new TraversabilityOcTreeNode();
    ++tree_size;
    created = true;
  }
  updateNodesRecurs(root, created, 0, codes.data(), codes.data() + codes.size());
}

void TraversabilityOcTree::updateNodesRecurs(TraversabilityOcTreeNode* node, bool just_created,
                                             unsigned int depth, std::uint64_t* lo,
                                             std::uint64_t* hi) {
  if (!just_created && !nodeHasChildren(node)) {
    // What OctoMap's search finds for these keys (their voxel, or a pruned node above them):
    // where an update would go towards the clamping bound it already holds, updateNode stops.
    const float value = node->getLogOdds();
    hi = std::remove_if(lo, hi, [&](std::uint64_t code) {
      const float update = (code & 1) != 0 ? prob_hit_log : prob_miss_log;
      return (update >= 0 && value >= clamping_thres_max) ||
             (update <= 0 && value <= clamping_thres_min);
    });
    if (lo == hi) return;
    if (depth < tree_depth) expandNode(node);  // (a pruned node: its copies below)
  }
  if (depth == tree_depth) {  // (one key: they are distinct)
    updateNodeLogOdds(node, (*lo & 1) != 0 ? prob_hit_log : prob_miss_log);
    return;
  }
  const unsigned int shift = 3 * (tree_depth - 1 - depth) + 1;  // (+ 1: the occupied bit)
  forEachChildRun(lo, hi, shift, [&](unsigned int child, auto a, auto b) {
    const bool create = !nodeChildExists(node, child);
    if (create) createNodeChild(node, child);
    updateNodesRecurs(getNodeChild(node, child), create, depth + 1, a, b);
  });
}

void TraversabilityOcTree::updateInnerOccupancyRecurs(TraversabilityOcTreeNode* node,
                                                      unsigned int depth, const std::uint64_t* lo,
                                                      const std::uint64_t* hi) {
  if (!nodeHasChildren(node)) return;
  if (depth < tree_depth) {
    const unsigned int shift = 3 * (tree_depth - 1 - depth);
    forEachChildRun(lo, hi, shift, [&](unsigned int child, auto a, auto b) {
      if (nodeChildExists(node, child)) {
        updateInnerOccupancyRecurs(getNodeChild(node, child), depth + 1, a, b);
      }
    });
  }
  node->updateOccupancyChildren();
  node->updateTraversabilityChildren();
}

void TraversabilityOcTree::cropToKeyBox(const octomap::OcTreeKey& min_key,
                                        const octomap::OcTreeKey& max_key) {
  if (root == nullptr) return;
  const octomap::OcTreeKey root_key(tree_max_val, tree_max_val, tree_max_val);
  if (cropRecurs(root, root_key, 0, min_key, max_key)) {
    clear();
    return;
  }
  tree_size = calcNumNodes();
  size_changed = true;
  updateInnerOccupancy();
}

bool TraversabilityOcTree::cropRecurs(TraversabilityOcTreeNode* node, const octomap::OcTreeKey& key,
                                      unsigned int depth, const octomap::OcTreeKey& min_key,
                                      const octomap::OcTreeKey& max_key,
                                      detail::OctreeTileStore* keep) {
  // Keys covered by the node: a leaf covers its own key; a node at depth d < tree_depth covers
  // [key - half, key + half - 1] with half = tree_max_val >> d (children at key +- half / 2).
  bool inside = true;
  for (int a = 0; a < 3; ++a) {
    long lo = key[a], hi = key[a];
    if (depth < tree_depth) {
      const long half = static_cast<long>(tree_max_val >> depth);
      lo = key[a] - half;
      hi = key[a] + half - 1;
    }
    if (hi < min_key[a] || lo > max_key[a]) {  // entirely outside
      if (keep != nullptr) keepSubtree(node, key, depth, *keep);
      return true;
    }
    if (lo < min_key[a] || hi > max_key[a]) inside = false;
  }
  if (inside) return false;
  if (!nodeHasChildren(node)) {
    // A pruned node straddling the box: split it so the part inside survives.
    expandNode(node);
  }
  const octomap::key_type offset = static_cast<octomap::key_type>(tree_max_val >> (depth + 1));
  for (unsigned int i = 0; i < 8; ++i) {
    if (!nodeChildExists(node, i)) continue;
    octomap::OcTreeKey child_key;
    octomap::computeChildKey(i, offset, key, child_key);
    TraversabilityOcTreeNode* child = getNodeChild(node, i);
    if (cropRecurs(child, child_key, depth + 1, min_key, max_key, keep)) {
      deleteNodeRecurs(child);
      node->children[i] = nullptr;
    }
  }
  if (!nodeHasChildren(node)) {
    delete[] node->children;
    node->children = nullptr;
    return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// Statistics (insertion: octree_insert.cpp)

OctreeStats computeStats(const TraversabilityOcTree& tree) {
  OctreeStats s;
  s.nodes = tree.size();
  s.memory_bytes = tree.memoryUsage();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    ++s.leaves;
    if (tree.isNodeOccupied(*it)) ++s.occupied_leaves;
    if (it->hasTraversability()) {
      ++s.traversability_leaves;
      if (it->getNonTraversableProbability() >= 0.5f) ++s.non_traversable_leaves;
    }
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// Files

namespace {

// A ColorOcTree that can be built node by node from another tree (needs the protected root).
class ColourCopy : public octomap::ColorOcTree {
 public:
  explicit ColourCopy(double resolution) : ColorOcTree(resolution) {}

  void copyFrom(const TraversabilityOcTree& src) {
    clear();
    if (src.getRoot() == nullptr) return;
    root = new octomap::ColorOcTreeNode();
    ++tree_size;
    copyRecurs(src, src.getRoot(), root);
    size_changed = true;
  }

 private:
  void copyRecurs(const TraversabilityOcTree& src, const TraversabilityOcTreeNode* from,
                  octomap::ColorOcTreeNode* to) {
    to->setLogOdds(from->getLogOdds());
    const auto rgb = traversabilityColourRgb(from->getNonTraversableProbability());
    to->setColor(rgb[0], rgb[1], rgb[2]);
    if (!src.nodeHasChildren(from)) return;
    for (unsigned int i = 0; i < 8; ++i) {
      if (src.nodeChildExists(from, i)) {
        copyRecurs(src, src.getNodeChild(from, i), createNodeChild(to, i));
      }
    }
  }
};

}  // namespace

void writeTraversabilityOt(const TraversabilityOcTree& tree, const std::string& path) {
  io::writeFileAtomically(path, [&](std::ostream& out) {
    if (!tree.write(out)) {
      throw std::runtime_error("cannot write '" + path + "': OctoMap failed to write the tree");
    }
  });
}

void writeOccupancyBt(const TraversabilityOcTree& tree, const std::string& path) {
  io::writeFileAtomically(path, [&](std::ostream& out) {
    // AbstractOccupancyOcTree::writeBinaryConst's header, but with id OcTree: the binary data
    // is occupancy only, so every reader (octovis, octomap_server) takes it as a plain OcTree.
    out << "# Octomap OcTree binary file\n"
        << "# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
        << "id OcTree\n"
        << "size " << tree.size() << "\n"
        << "res " << tree.getResolution() << "\n"
        << "data\n";
    tree.writeBinaryData(out);
  });
}

void writeColourOt(const TraversabilityOcTree& tree, const std::string& path) {
  ColourCopy colour(tree.getResolution());
  colour.copyFrom(tree);
  io::writeFileAtomically(path, [&](std::ostream& out) {
    if (!colour.write(out)) {
      throw std::runtime_error("cannot write '" + path + "': OctoMap failed to write the tree");
    }
  });
}

namespace {

std::runtime_error otError(const std::string& path, const std::string& why) {
  return std::runtime_error("cannot read octree '" + path + "': " + why);
}

// Opens an .ot file and parses its header (as AbstractOcTree::readHeader does, without its
// messages on stderr), leaving the stream at the first node.
std::ifstream openOt(const std::string& path, OtHeader& header) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw otError(path, "cannot open the file");
  std::string line;
  std::getline(in, line);
  if (line.rfind("# Octomap OcTree file", 0) != 0) {
    throw otError(path, "not an OctoMap .ot file (first line '" + line.substr(0, 40) + "')");
  }
  long long size = -1;
  bool data = false;
  std::string token;
  while (!data && in >> token) {
    if (token == "data") {
      data = true;
    } else if (token == "id") {
      in >> header.id;
    } else if (token == "res") {
      in >> header.resolution;
    } else if (token == "size") {
      in >> size;
    }
    if (token == "data" || token.rfind('#', 0) == 0 || token == "id" || token == "res" ||
        token == "size") {
      std::getline(in, line);  // rest of the line (comments; the newline before the data)
    }
  }
  if (!data) throw otError(path, "the header has no 'data' line");
  if (!(header.resolution > 0) || size < 0) {
    throw otError(path, "the header has no valid 'res' and 'size'");
  }
  header.nodes = static_cast<std::size_t>(size);
  return in;
}

// Reads the header's number of nodes into `tree`; a file that ends early or holds another
// number of nodes is an error. The stream throws at its end: OctoMap's readNodesRecurs would
// otherwise go on with child bits it could not read (uninitialized) and build nodes from them.
template <class Tree>
void readOtNodes(const std::string& path, std::ifstream& in, const OtHeader& header, Tree& tree) {
  bool ended = false;
  if (header.nodes > 0) {
    in.exceptions(std::ios::failbit | std::ios::badbit);
    try {
      tree.readData(in);
    } catch (const std::ios_base::failure&) {
      ended = true;  // reported below with the nodes read
    }
  }
  if (ended || tree.size() != header.nodes) {
    throw otError(path, "truncated or corrupt data (" + std::to_string(tree.size()) + " of " +
                            std::to_string(header.nodes) + " nodes read)");
  }
}

template <class Tree>
std::unique_ptr<Tree> readOtNodesInto(const std::string& path, std::ifstream& in, const OtHeader& header) {
  auto tree = std::make_unique<Tree>(header.resolution);
  readOtNodes(path, in, header, *tree);
  return tree;
}

std::runtime_error wrongOtType(const std::string& path, const OtHeader& header, const std::string& wanted) {
  return otError(path, "it holds a " + (header.id.empty() ? std::string("tree of no type") : header.id) +
                           ", not a " + wanted);
}

template <class Tree>
std::unique_ptr<Tree> readOtOfType(const std::string& path, const std::string& type) {
  OtHeader header;
  std::ifstream in = openOt(path, header);
  if (header.id != type) throw wrongOtType(path, header, type);
  return readOtNodesInto<Tree>(path, in, header);
}

}  // namespace

OtHeader readOtHeader(const std::string& path) {
  OtHeader header;
  openOt(path, header);
  return header;
}

std::unique_ptr<TraversabilityOcTree> readTraversabilityOt(const std::string& path) {
  return readOtOfType<TraversabilityOcTree>(path, "TraversabilityOcTree");
}

std::unique_ptr<octomap::ColorOcTree> readColourOt(const std::string& path) {
  return readOtOfType<octomap::ColorOcTree>(path, "ColorOcTree");
}

AnyOt readAnyOt(const std::string& path) {
  OtHeader header;
  std::ifstream in = openOt(path, header);
  AnyOt any;
  if (header.id == "TraversabilityOcTree") {
    any.traversability = readOtNodesInto<TraversabilityOcTree>(path, in, header);
  } else if (header.id == "ColorOcTree") {
    any.colour = readOtNodesInto<octomap::ColorOcTree>(path, in, header);
  } else {
    throw wrongOtType(path, header, "TraversabilityOcTree or a ColorOcTree");
  }
  return any;
}

}  // namespace upd::maps
