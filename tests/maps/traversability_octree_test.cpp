// The OctoMap tree with traversability: insertion, worst-child inner nodes, .ot / .bt files that
// OctoMap reloads, the update box that bounds memory, and a real OctoMap file.
#include "maps/frames.h"
#include "test_data.h"
#include "upd/maps/traversability_octree.h"

#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>

namespace core = upd::core;

using upd::core::Label;
using upd::maps::FusionParams;
using upd::maps::OctreeParams;
using upd::maps::TraversabilityOcTree;
using upd::maps::TraversabilityOcTreeNode;
using upd::test::Frame;
using upd::test::TempDir;

namespace {

using LeafId = std::tuple<int, int, int, unsigned>;  // key x, y, z, depth

const Eigen::Vector3d kSensor(0.0, 0.0, 1.0);
constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
const octomap::point3d kObstacle(3.05f, 0.05f, 0.35f);
const octomap::point3d kGround(2.05f, 0.05f, 0.05f);

OctreeParams fixedParams() {
  OctreeParams p;
  p.resolution_m = 0.1;
  p.follow_robot = false;
  p.extent_m = 20.0;
  p.height_m = 6.0;
  return p;
}

// Ground at z in [0, 0.1) over x in [1, 4), y in [-1, 1), traversable; a box face at x in
// [3, 3.1), y in [-0.2, 0.2), z in [0.1, 0.6), non-traversable. Points at voxel centres.
Frame scene() {
  Frame f;
  for (int i = 10; i < 40; ++i) {
    for (int j = -10; j < 10; ++j) {
      f.add((i + 0.5f) * 0.1f, (j + 0.5f) * 0.1f, 0.05f, core::Label::Traversable, 1.0f, 0.0f, 0.1f);
    }
  }
  for (int j = -2; j < 2; ++j) {
    for (int k = 1; k < 6; ++k) {
      f.add(3.05f, (j + 0.5f) * 0.1f, (k + 0.5f) * 0.1f, core::Label::NonTraversable, 0.8f, 1.2f, 1.0f);
    }
  }
  f.add(2.55f, 1.55f, 0.05f, core::Label::Unknown, NAN, NAN, NAN);  // beside the ground: occupancy only
  return f;
}

std::unique_ptr<TraversabilityOcTree> sceneTree(int frames = 3) {
  const OctreeParams p = fixedParams();
  auto tree = std::make_unique<TraversabilityOcTree>(p);
  const Frame f = scene();
  for (int k = 0; k < frames; ++k)
    upd::maps::insertScan(*tree, f.view(), kSensor, p, FusionParams{});
  return tree;
}

bool sameFloat(float a, float b) { return a == b || (std::isnan(a) && std::isnan(b)); }

struct LeafData {
  float logodds, trav, zeta, cost;
  unsigned observations;
  bool operator==(const LeafData& o) const {
    return logodds == o.logodds && sameFloat(trav, o.trav) && sameFloat(zeta, o.zeta) &&
           sameFloat(cost, o.cost) && observations == o.observations;
  }
};

std::map<LeafId, LeafData> leavesOf(const TraversabilityOcTree& t) {
  std::map<LeafId, LeafData> out;
  for (auto it = t.begin_leafs(), end = t.end_leafs(); it != end; ++it) {
    const auto k = it.getKey();
    out[{k[0], k[1], k[2], it.getDepth()}] = {it->getLogOdds(), it->getTraversabilityLogOdds(),
                                              it->getZetaMin(), it->getCostMean(),
                                              it->getObservations()};
  }
  return out;
}

template <class Tree>
std::set<LeafId> occupiedLeaves(const Tree& t) {
  std::set<LeafId> out;
  for (auto it = t.begin_leafs(), end = t.end_leafs(); it != end; ++it) {
    if (!t.isNodeOccupied(*it)) continue;
    const auto k = it.getKey();
    out.insert({k[0], k[1], k[2], it.getDepth()});
  }
  return out;
}

bool noTemporaryFiles(const TempDir& dir) {
  for (const auto& name : dir.listing()) {
    if (name.find(".tmp") != std::string::npos) return false;
  }
  return true;
}

}  // namespace

TEST(TraversabilityOctree, StoresTraversabilityBesideOccupancy) {
  const auto tree = sceneTree();
  const TraversabilityOcTreeNode* obstacle = tree->search(kObstacle);
  ASSERT_NE(obstacle, nullptr);
  EXPECT_TRUE(tree->isNodeOccupied(obstacle));
  EXPECT_NEAR(obstacle->getTraversabilityLogOdds(), 3 * 0.85, 1e-5);  // one update per frame
  EXPECT_GT(obstacle->getNonTraversableProbability(), 0.9f);
  EXPECT_FLOAT_EQ(obstacle->getZetaMin(), 0.8f);
  EXPECT_FLOAT_EQ(obstacle->getCostMean(), 1.0f);
  EXPECT_EQ(obstacle->getObservations(), 3u);

  const TraversabilityOcTreeNode* ground = tree->search(kGround);
  ASSERT_NE(ground, nullptr);
  EXPECT_TRUE(tree->isNodeOccupied(ground));
  EXPECT_LT(ground->getNonTraversableProbability(), 0.3f);
  EXPECT_FLOAT_EQ(ground->getZetaMin(), 1.0f);
  EXPECT_NEAR(ground->getCostMean(), 0.1f, 1e-6);

  // Unknown points make occupancy only.
  const TraversabilityOcTreeNode* unknown = tree->search(2.55, 1.55, 0.05);
  ASSERT_NE(unknown, nullptr);
  EXPECT_TRUE(tree->isNodeOccupied(unknown));
  EXPECT_FALSE(unknown->hasTraversability());
  EXPECT_TRUE(std::isnan(unknown->getNonTraversableProbability()));

  // A voxel the rays cross is free and has no traversability.
  const TraversabilityOcTreeNode* free_voxel = tree->search(1.05, 0.05, 0.55);
  ASSERT_NE(free_voxel, nullptr);
  EXPECT_FALSE(tree->isNodeOccupied(free_voxel));
  EXPECT_FALSE(free_voxel->hasTraversability());

  const auto stats = upd::maps::computeStats(*tree);
  EXPECT_EQ(stats.traversability_leaves, 30u * 20u + 4u * 5u);  // ground + box face
  EXPECT_EQ(stats.non_traversable_leaves, 4u * 5u);
  EXPECT_EQ(stats.occupied_leaves, 30u * 20u + 4u * 5u + 1u);  // + the Unknown point
}

// Occupancy of the voxel at c in tree a equals that in tree b, for every leaf of a (a pruned
// leaf is looked up at its centre: the same value covers the whole node).
template <class A, class B>
void expectSameOccupancy(const A& a, const B& b, const char* what) {
  std::size_t leaves = 0;
  for (auto it = a.begin_leafs(), end = a.end_leafs(); it != end; ++it, ++leaves) {
    const auto* other = b.search(it.getCoordinate());
    ASSERT_NE(other, nullptr) << what << " at " << it.getCoordinate();
    EXPECT_FLOAT_EQ(it->getLogOdds(), other->getLogOdds()) << what << " at " << it.getCoordinate();
  }
  EXPECT_GT(leaves, 100u) << what;
}

// The insert works out keys and runs in fixed chunks of points, in parallel: a scan of several
// chunks, with runs of one voxel across the chunk boundaries, gives the same tree (occupancy and
// traversability, byte for byte) on one thread and on two, and OctoMap's own occupancy.
TEST(TraversabilityOctree, InsertIsTheSameOnOneThreadAndTwoAcrossChunks) {
  Frame f;
  for (int row = 0; row < 240; ++row) {  // image rows across the ground and up a wall
    for (int col = 0; col < 250; ++col) {
      const float u = 0.004f * static_cast<float>(col), v = 0.01f * static_cast<float>(row);
      if ((row * 250 + col) % 211 == 5) {
        f.add(kNan, kNan, kNan, core::Label::Unknown);
        continue;
      }
      const bool wall = v > 1.6f;
      const core::Label l = (row + col) % 13 == 0  ? core::Label::Unknown
                      : wall || col % 5 == 0 ? core::Label::NonTraversable
                                             : core::Label::Traversable;
      f.add(wall ? 1.6f + 0.001f * col : 0.4f + v, -0.5f + u, wall ? v - 1.6f : 0.01f, l,
            0.9f + 0.0003f * col, 0.01f * row, 0.001f * (row + col));
    }
  }
  ASSERT_GT(f.x.size(), 3u * 16384u);  // several chunks
  for (const bool discretize : {true, false}) {
    OctreeParams p = fixedParams();
    p.discretize = discretize;
    std::string bytes[2];
    for (int threads = 1; threads <= 2; ++threads) {
#ifdef _OPENMP
      omp_set_num_threads(threads);
#endif
      TraversabilityOcTree tree(p);
      const auto stats = upd::maps::insertScan(tree, f.view(), kSensor, p, FusionParams{});
      EXPECT_EQ(stats.points_inserted + stats.points_invalid, f.x.size());
      std::ostringstream out;
      tree.write(out);
      bytes[threads - 1] = out.str();
      if (threads == 1) {
        octomap::OcTree reference(p.resolution_m);
        octomap::Pointcloud cloud;
        for (std::size_t i = 0; i < f.x.size(); ++i) {
          if (std::isfinite(f.x[i])) cloud.push_back(f.x[i], f.y[i], f.z[i]);
        }
        reference.insertPointCloud(cloud, octomap::point3d(0.f, 0.f, 1.f), p.max_range_m, false,
                                   discretize);
        expectSameOccupancy(tree, reference, discretize ? "discretized" : "per point");
        expectSameOccupancy(reference, tree, discretize ? "discretized" : "per point");
      }
    }
    EXPECT_EQ(bytes[0], bytes[1]) << (discretize ? "discretized" : "one ray per point");
  }
}

// The insert updates only the inner nodes above the voxels a frame changes, so that a frame's
// cost does not grow with the map: frame after frame of a sensor moving over a noisy floor
// (its points on both sides of the voxel boundary z = 0) towards a wall, the box moving and
// the tiles kept outside it coming back, the tree is byte for byte what an update of every
// inner node gives.
TEST(TraversabilityOctree, InsertUpdatesTheInnerNodesAsAWholeTreeUpdate) {
  OctreeParams p = fixedParams();  // (0.1 m voxels) in a small box that follows the sensor
  p.follow_robot = true;
  p.extent_m = 4.0;
  p.keep_outside_box = true;
  TraversabilityOcTree tree(p);
  for (int step = 0; step < 40; ++step) {
    const double x = step < 20 ? 0.3 * step : 0.3 * (39 - step);  // out and back
    Frame f;
    for (int u = 0; u < 30; ++u) {
      for (int v = 0; v < 20; ++v) {
        const float fx = static_cast<float>(x + 0.5 + 0.05 * u), fy = -0.5f + 0.05f * v;
        f.add(fx, fy, 0.003f * static_cast<float>((u + 2 * v) % 3 - 1),
              (u * v) % 17 == 0 ? core::Label::NonTraversable : core::Label::Traversable, 0.97f,
              0.05f, 0.2f);
      }
      f.add(static_cast<float>(x + 2.0), 0.1f, 0.05f * static_cast<float>(u),
            core::Label::NonTraversable, 0.8f, 1.2f, 1.0f);
    }
    upd::maps::insertScan(tree, f.view(), {x, 0.0, 0.6}, p, FusionParams{});
    std::ostringstream inserted, whole;
    tree.write(inserted);
    tree.updateInnerOccupancy();
    tree.write(whole);
    ASSERT_EQ(inserted.str(), whole.str()) << "frame " << step;
  }
  EXPECT_GT(tree.keptTiles(), 0u);
}

// updateNodes gives the tree OctoMap's updateNode calls one after the other give, on a tree
// with pruned nodes (saturated free space collapsed), voxels at both clamping bounds, voxels
// between them and space with no node: the early stop at a saturated voxel or pruned node, the
// expansion of a pruned node, the nodes created; byte for byte.
TEST(TraversabilityOctree, UpdateNodesIsOctomapsUpdateNodeOneAfterTheOther) {
  std::unique_ptr<TraversabilityOcTree> trees[2] = {sceneTree(12), sceneTree(12)};
  std::size_t pruned = 0;
  for (auto& t : trees) {
    const std::size_t before = t->size();
    t->prune();
    pruned = before - t->size();
    t->updateNode(t->coordToKey(2.55, 0.05, 0.35), true, true);  // (one voxel between the bounds)
  }
  ASSERT_GT(pruned, 100u);
  std::vector<octomap::OcTreeKey> free, occupied;
  for (int i = -5; i < 45; ++i) {
    for (int j = -12; j < 12; ++j) {
      for (int k = -2; k < 12; ++k) {
        const octomap::OcTreeKey key = trees[0]->coordToKey(0.1 * i + 0.05, 0.1 * j + 0.05,
                                                            0.1 * k + 0.05);
        if ((i + 2 * j + 3 * k) % 7 == 0) continue;  // (keys left alone)
        // (occupied keys on one side of the sensor and at the far end only: pruned free space
        // on the other side, saturated, gets free keys alone and stays pruned)
        const bool hit = (i >= 30 || (j < 0 && i < 10)) && (i * j + k) % 3 == 0;
        (hit ? occupied : free).push_back(key);
      }
    }
  }
  trees[0]->updateNodes(free, occupied);
  for (const auto& k : free) trees[1]->updateNode(k, false, true);
  for (const auto& k : occupied) trees[1]->updateNode(k, true, true);
  std::ostringstream batched, one_by_one;
  trees[0]->write(batched);
  trees[1]->write(one_by_one);
  EXPECT_EQ(trees[0]->size(), trees[1]->size());
  EXPECT_EQ(batched.str(), one_by_one.str());
}

// The insert computes a block of points' voxel keys at once, not by OctoMap's coordToKeyChecked:
// points on and beside voxel boundaries, at negative coordinates and at -0, each end in the
// voxel OctoMap's own key names (occupied, with its traversability); points that are not
// finite are counted and left out.
TEST(TraversabilityOctree, PointsEndInTheVoxelsOfOctomapsKeys) {
  const OctreeParams p = fixedParams();
  TraversabilityOcTree tree(p);
  const float edges[] = {-0.2f, -0.1f, -0.05f, -1e-7f, -0.0f, 0.0f, 1e-7f, 0.1f, 0.2f, 0.3f};
  Frame f;
  std::vector<octomap::point3d> ends;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      const auto fi = static_cast<float>(i), fj = static_cast<float>(j);
      const octomap::point3d e(-2.0f + 0.5f * fi + edges[j], -2.0f + 0.5f * fj + edges[i],
                               edges[(i + j) % 10]);
      f.add(e.x(), e.y(), e.z(), core::Label::Traversable);
      ends.push_back(e);
    }
  }
  f.add(kNan, 0.f, 0.f, core::Label::Traversable);
  f.add(std::numeric_limits<float>::infinity(), 0.f, 0.f, core::Label::Traversable);
  const auto stats = upd::maps::insertScan(tree, f.view(), {0.0, 0.0, 1.0}, p, FusionParams{});
  EXPECT_EQ(stats.points_invalid, 2u);
  for (const octomap::point3d& e : ends) {
    const TraversabilityOcTreeNode* node = tree.search(e);  // (OctoMap's key of e)
    ASSERT_NE(node, nullptr) << e;
    EXPECT_TRUE(tree.isNodeOccupied(node)) << e;
    EXPECT_TRUE(node->hasTraversability()) << e;
  }
}

TEST(TraversabilityOctree, DiscretizedInsertMatchesOctomapsOwnAndCountsEveryPoint) {
  // Nine points per ground voxel, off the voxel centres, and a wall: many points per end
  // voxel, as in a depth image.
  Frame f;
  for (int i = 10; i < 30; ++i) {
    for (int j = -8; j < 8; ++j) {
      for (int k = 0; k < 9; ++k) {
        f.add((i + 0.1f + 0.1f * (k % 3)) * 0.1f, (j + 0.15f + 0.3f * (k / 3)) * 0.1f,
              0.02f + 0.005f * k, k == 4 ? core::Label::NonTraversable : core::Label::Traversable, 1.0f, 0.0f,
              0.1f);
      }
    }
  }
  for (int j = -3; j < 3; ++j) {
    for (int k = 1; k < 6; ++k) {
      f.add(3.07f, (j + 0.4f) * 0.1f, (k + 0.6f) * 0.1f, core::Label::NonTraversable, 0.8f, 1.2f, 1.0f);
    }
  }
  for (const bool discretize : {true, false}) {
    OctreeParams p = fixedParams();
    p.discretize = discretize;
    TraversabilityOcTree ours(p);
    upd::maps::insertScan(ours, f.view(), kSensor, p, FusionParams{});
    // OctoMap's own insert of the same points with the same option.
    octomap::OcTree reference(p.resolution_m);
    octomap::Pointcloud cloud;
    for (std::size_t i = 0; i < f.x.size(); ++i) cloud.push_back(f.x[i], f.y[i], f.z[i]);
    reference.insertPointCloud(cloud, octomap::point3d(0.f, 0.f, 1.f), p.max_range_m, false,
                               discretize);
    const char* what = discretize ? "discretized" : "one ray per point";
    expectSameOccupancy(ours, reference, what);
    expectSameOccupancy(reference, ours, what);
    // Traversability still counts every labelled point of a voxel: 1 of 9 non-traversable.
    const TraversabilityOcTreeNode* ground = ours.search(1.55, 0.05, 0.05);
    ASSERT_NE(ground, nullptr) << what;
    EXPECT_TRUE(ground->hasTraversability()) << what;
    EXPECT_LT(ground->getNonTraversableProbability(), 0.5f) << what;
    EXPECT_EQ(ground->getObservations(), 1u) << what;
  }
}

TEST(TraversabilityOctree, InnerNodesHoldTheWorstChild) {
  const auto tree = sceneTree();
  float max_trav = -INFINITY, min_zeta = INFINITY, max_cost = -INFINITY;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
    if (!it->hasTraversability()) continue;
    max_trav = std::max(max_trav, it->getTraversabilityLogOdds());
    min_zeta = std::min(min_zeta, it->getZetaMin());
    max_cost = std::max(max_cost, it->getCostMean());
  }
  const TraversabilityOcTreeNode* root = tree->getRoot();
  ASSERT_NE(root, nullptr);
  EXPECT_FLOAT_EQ(root->getTraversabilityLogOdds(), max_trav);
  EXPECT_FLOAT_EQ(root->getZetaMin(), min_zeta);
  EXPECT_FLOAT_EQ(root->getCostMean(), max_cost);
  // A coarse node (1.6 m) that holds both the obstacle and some ground reports the obstacle.
  const TraversabilityOcTreeNode* coarse = tree->search(kObstacle, 12);
  ASSERT_NE(coarse, nullptr);
  EXPECT_GT(coarse->getNonTraversableProbability(), 0.9f);
}

TEST(TraversabilityOctree, OtReloadsAsTraversabilityOcTreeWithTheSameLeaves) {
  const auto tree = sceneTree();
  TempDir dir("ot");
  const std::string path = dir.file("map.ot");
  upd::maps::writeTraversabilityOt(*tree, path);
  EXPECT_TRUE(noTemporaryFiles(dir));

  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(path));
  ASSERT_NE(read, nullptr);
  EXPECT_EQ(read->getTreeType(), "TraversabilityOcTree");
  auto* reloaded = dynamic_cast<TraversabilityOcTree*>(read.get());
  ASSERT_NE(reloaded, nullptr);
  EXPECT_DOUBLE_EQ(reloaded->getResolution(), tree->getResolution());
  EXPECT_EQ(reloaded->size(), tree->size());
  const auto a = leavesOf(*tree);
  const auto b = leavesOf(*reloaded);
  EXPECT_EQ(a.size(), b.size());
  EXPECT_TRUE(a == b);
  EXPECT_FLOAT_EQ(reloaded->getRoot()->getTraversabilityLogOdds(),
                  tree->getRoot()->getTraversabilityLogOdds());

  const auto again = upd::maps::readTraversabilityOt(path);
  EXPECT_TRUE(leavesOf(*again) == a);

  // A truncated file is an error, not a smaller map.
  const auto full = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, full / 2);
  try {
    upd::maps::readTraversabilityOt(path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(TraversabilityOctree, BtReloadsAsOcTreeWithTheSameOccupiedLeaves) {
  const auto tree = sceneTree();
  TempDir dir("bt");
  const std::string path = dir.file("map.bt");
  upd::maps::writeOccupancyBt(*tree, path);
  EXPECT_TRUE(noTemporaryFiles(dir));
  std::ifstream in(path);
  std::string first, line;
  std::getline(in, first);
  EXPECT_EQ(first, "# Octomap OcTree binary file");
  bool has_id = false;
  while (std::getline(in, line) && line != "data") has_id |= line == "id OcTree";
  EXPECT_TRUE(has_id);

  octomap::OcTree reloaded(path);
  EXPECT_DOUBLE_EQ(reloaded.getResolution(), tree->getResolution());
  EXPECT_EQ(reloaded.size(), tree->size());
  const auto occ = occupiedLeaves(*tree);
  EXPECT_GT(occ.size(), 600u);
  EXPECT_EQ(occupiedLeaves(reloaded), occ);
  // Writing the .bt does not change the tree (no max-likelihood conversion, no pruning).
  EXPECT_NEAR(tree->search(kObstacle)->getTraversabilityLogOdds(), 3 * 0.85, 1e-5);
  EXPECT_THROW(upd::maps::readTraversabilityOt(path), std::runtime_error);
}

TEST(TraversabilityOctree, ColourOtIsAColorOcTreeColouredByTraversability) {
  const auto tree = sceneTree();
  TempDir dir("colour");
  const std::string path = dir.file("colour.ot");
  upd::maps::writeColourOt(*tree, path);
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(path));
  ASSERT_NE(read, nullptr);
  auto* colour = dynamic_cast<octomap::ColorOcTree*>(read.get());
  ASSERT_NE(colour, nullptr);
  EXPECT_EQ(occupiedLeaves(*colour), occupiedLeaves(*tree));
  const auto red = colour->search(kObstacle)->getColor();
  EXPECT_GT(red.r, 200);
  EXPECT_LT(red.g, 60);
  const auto green = colour->search(kGround)->getColor();
  EXPECT_LT(green.r, 150);
  EXPECT_GT(green.g, 200);
  const auto grey = colour->search(2.55, 1.55, 0.05)->getColor();
  EXPECT_EQ(grey.r, 128);
  EXPECT_EQ(grey.g, 128);
  // It is not a traversability tree.
  try {
    upd::maps::readTraversabilityOt(path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("ColorOcTree"), std::string::npos) << e.what();
  }
}

TEST(TraversabilityOctree, ColourOtReloadsWholeOrNotAtAll) {
  const auto tree = sceneTree();
  TempDir dir("colour_read");
  const std::string path = dir.file("map.ot");
  upd::maps::writeColourOt(*tree, path);

  const upd::maps::OtHeader header = upd::maps::readOtHeader(path);
  EXPECT_EQ(header.id, "ColorOcTree");
  EXPECT_DOUBLE_EQ(header.resolution, tree->getResolution());
  EXPECT_EQ(header.nodes, tree->size());
  const auto whole = upd::maps::readColourOt(path);
  EXPECT_EQ(whole->size(), tree->size());
  EXPECT_EQ(occupiedLeaves(*whole), occupiedLeaves(*tree));

  // A file cut anywhere in its nodes is an error naming the file and the nodes read, never a
  // smaller or garbled map (OctoMap's own reader builds nodes from the bits it could not read).
  const std::string full = upd::test::readFileBytes(path);
  for (const double share : {0.1, 0.5, 0.9, 0.999}) {
    const std::string cut_path = dir.file("cut.ot");
    std::ofstream(cut_path, std::ios::binary)
        << full.substr(0, static_cast<std::size_t>(share * double(full.size())));
    try {
      upd::maps::readColourOt(cut_path);
      ADD_FAILURE() << "no exception at " << share;
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(cut_path), std::string::npos) << what;
      EXPECT_NE(what.find("of " + std::to_string(tree->size()) + " nodes read"), std::string::npos)
          << what;
    }
  }
  // Another tree type is named.
  const std::string trav = dir.file("trav.ot");
  upd::maps::writeTraversabilityOt(*tree, trav);
  EXPECT_EQ(upd::maps::readOtHeader(trav).id, "TraversabilityOcTree");
  EXPECT_THROW(upd::maps::readColourOt(trav), std::runtime_error);
}

TEST(TraversabilityOctree, AnyOtReadsEitherTreeTheHeaderNamesAndRefusesAnother) {
  const auto tree = sceneTree();
  TempDir dir("any_ot");
  const std::string trav = dir.file("map_traversability.ot");
  const std::string colour = dir.file("map.ot");
  upd::maps::writeTraversabilityOt(*tree, trav);
  upd::maps::writeColourOt(*tree, colour);

  const upd::maps::AnyOt a = upd::maps::readAnyOt(trav);
  ASSERT_TRUE(a.traversability);
  EXPECT_FALSE(a.colour);
  EXPECT_EQ(occupiedLeaves(*a.traversability), occupiedLeaves(*tree));
  const upd::maps::AnyOt b = upd::maps::readAnyOt(colour);
  ASSERT_TRUE(b.colour);
  EXPECT_FALSE(b.traversability);
  EXPECT_EQ(occupiedLeaves(*b.colour), occupiedLeaves(*tree));

  // A plain OcTree .ot (another tool's) is named, with the file.
  const std::string plain = dir.file("plain.ot");
  octomap::OcTree occupancy(tree->getResolution());
  occupancy.updateNode(octomap::point3d(0.1f, 0.1f, 0.1f), true);
  ASSERT_TRUE(occupancy.write(plain));
  try {
    upd::maps::readAnyOt(plain);
    ADD_FAILURE() << "a plain OcTree was read";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(plain), std::string::npos) << what;
    EXPECT_NE(what.find("holds a OcTree"), std::string::npos) << what;
  }
}

TEST(TraversabilityOctree, RealOctomapFileLoadsAndRoundTrips) {
  UPD_REQUIRE_SHARED_FILE(path, "octomap/geb079.bt");
  octomap::OcTree reference(path);
  ASSERT_GT(reference.size(), 0u);
  TraversabilityOcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(path));
  EXPECT_DOUBLE_EQ(tree.getResolution(), reference.getResolution());
  EXPECT_EQ(tree.size(), reference.size());
  const auto occ = occupiedLeaves(reference);
  EXPECT_GT(occ.size(), 1000u);
  EXPECT_EQ(occupiedLeaves(tree), occ);
  EXPECT_EQ(upd::maps::computeStats(tree).traversability_leaves, 0u);

  TempDir dir("geb");
  upd::maps::writeOccupancyBt(tree, dir.file("geb.bt"));
  octomap::OcTree again(dir.file("geb.bt"));
  EXPECT_EQ(occupiedLeaves(again), occ);
  upd::maps::writeTraversabilityOt(tree, dir.file("geb.ot"));
  EXPECT_EQ(occupiedLeaves(*upd::maps::readTraversabilityOt(dir.file("geb.ot"))), occ);
}

// A voxel's traversability is updated only by points that mark it hit, as its occupancy: a
// frame whose points lie beyond max_range of the sensor, or outside the update box, leaves the
// voxels they fall in as they were, in both insert modes.
TEST(TraversabilityOctree, PointsBeyondRangeOrOutsideTheBoxLeaveTraversabilityAlone) {
  for (const bool discretize : {true, false}) {
    OctreeParams p = fixedParams();  // a fixed box of 20 x 20 x 6 m around the origin
    p.discretize = discretize;
    p.max_range_m = 3.0;
    TraversabilityOcTree tree(p);
    const auto wall = [](float x, core::Label l) {
      Frame f;
      for (int k = 0; k < 5; ++k) f.add(x, 0.05f, 0.15f + 0.1f * k, l, 0.8f, 1.2f, 1.0f);
      return f;
    };
    // Seen once within range (traversable), then from 5 m away as non-traversable.
    upd::maps::insertScan(tree, wall(2.05f, core::Label::Traversable).view(), {0.0, 0.0, 0.5}, p,
                          FusionParams{});
    upd::maps::insertScan(tree, wall(2.05f, core::Label::NonTraversable).view(),
                          {-3.0, 0.0, 0.5}, p, FusionParams{});
    const TraversabilityOcTreeNode* node = tree.search(2.05, 0.05, 0.35);
    ASSERT_NE(node, nullptr);
    EXPECT_EQ(node->getObservations(), 1u) << discretize;
    EXPECT_LT(node->getNonTraversableProbability(), 0.5f) << discretize;
    // A wall beyond the box's edge (x = 10 m), seen from within range: no voxel of it.
    upd::maps::insertScan(tree, wall(10.05f, core::Label::NonTraversable).view(), {8.0, 0.0, 0.5},
                          p, FusionParams{});
    EXPECT_EQ(tree.search(10.05, 0.05, 0.35), nullptr) << discretize;
  }
}

TEST(TraversabilityOctree, UpdateBoxFollowsTheRobotAndBoundsMemory) {
  OctreeParams p;
  p.resolution_m = 0.2;
  p.max_range_m = 6.0;
  p.follow_robot = true;
  p.extent_m = 12.0;
  p.height_m = 4.0;
  TraversabilityOcTree tree(p);
  std::size_t nodes_at_100m = 0, max_nodes = 0;
  int moves = 0;
  for (int step = 0; step <= 1000; ++step) {
    const double x = step;  // 1 m per frame along x for 1 km
    Frame f;
    for (int u = 0; u < 20; ++u) {
      for (int v = 0; v < 11; ++v) {
        f.add(static_cast<float>(x + 1.1 + 0.2 * u), static_cast<float>(-1.1 + 0.2 * v), 0.1f,
              (u * 11 + v) % 13 == 0 ? core::Label::NonTraversable : core::Label::Traversable);
      }
    }
    const auto s = upd::maps::insertScan(tree, f.view(), {x, 0.0, 0.5}, p, FusionParams{});
    moves += s.window_moved ? 1 : 0;
    max_nodes = std::max(max_nodes, tree.size());
    if (step == 100) nodes_at_100m = tree.size();
  }
  EXPECT_GT(moves, 100);
  ASSERT_GT(nodes_at_100m, 0u);
  EXPECT_LT(max_nodes, 2 * nodes_at_100m);  // no growth with distance
  EXPECT_EQ(tree.calcNumNodes(), tree.size());
  // Every leaf lies inside the current box.
  const octomap::point3d bmin = tree.getBBXMin(), bmax = tree.getBBXMax();
  const double tol = p.resolution_m;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const double half = 0.5 * it.getSize();
    ASSERT_GE(it.getX() + half, bmin.x() - tol);
    ASSERT_LE(it.getX() - half, bmax.x() + tol);
    ASSERT_GE(it.getY() + half, bmin.y() - tol);
    ASSERT_LE(it.getY() - half, bmax.y() + tol);
  }
  // The start is gone, the robot's surroundings are mapped.
  EXPECT_EQ(tree.search(1.2, 0.0, 0.1), nullptr);
  const TraversabilityOcTreeNode* ahead = tree.search(1002.2, 0.1, 0.1);
  ASSERT_NE(ahead, nullptr);
  EXPECT_TRUE(ahead->hasTraversability());
}

TEST(TraversabilityOctree, FixedBoxKeepsTheTreeInside) {
  OctreeParams p;
  p.resolution_m = 0.1;
  p.follow_robot = false;
  p.extent_m = 4.0;
  p.height_m = 2.0;
  TraversabilityOcTree tree(p);
  Frame f;
  f.add(1.05f, 0.05f, 0.05f, core::Label::NonTraversable);
  f.add(5.05f, 0.05f, 0.05f, core::Label::NonTraversable);  // outside the box
  upd::maps::insertScan(tree, f.view(), {0.0, 0.0, 0.5}, p, FusionParams{});
  ASSERT_NE(tree.search(1.05, 0.05, 0.05), nullptr);
  EXPECT_TRUE(tree.search(1.05, 0.05, 0.05)->hasTraversability());
  EXPECT_EQ(tree.search(5.05, 0.05, 0.05), nullptr);
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    EXPECT_LE(std::abs(it.getX()), 2.0 + 1e-6);
  }
}

TEST(TraversabilityOctree, CroppingDeletesOutsideAndSplitsStraddlingNodes) {
  TraversabilityOcTree tree(0.1);
  // A pruned 0.8 m block of identical free voxels, then crop through its middle.
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) {
      for (int k = 0; k < 8; ++k)
        tree.updateNode((i + 0.5) * 0.1, (j + 0.5) * 0.1, (k + 0.5) * 0.1, false);
    }
  }
  tree.prune();
  ASSERT_EQ(tree.getNumLeafNodes(), 1u);
  tree.cropToKeyBox(tree.coordToKey(0.05, 0.05, 0.05), tree.coordToKey(0.35, 0.75, 0.75));
  // The 0.8 m leaf straddled the box: split into eight 0.4 m blocks, the four inside kept.
  EXPECT_EQ(tree.getNumLeafNodes(), 4u);
  EXPECT_EQ(tree.calcNumNodes(), tree.size());
  EXPECT_NE(tree.search(0.35, 0.75, 0.75), nullptr);
  EXPECT_EQ(tree.search(0.45, 0.05, 0.05), nullptr);
  tree.cropToKeyBox(tree.coordToKey(5.0, 5.0, 5.0), tree.coordToKey(6.0, 6.0, 6.0));
  EXPECT_EQ(tree.size(), 0u);
}

TEST(TraversabilityOctree, WritesFailCleanlyAndParametersAreChecked) {
  const auto tree = sceneTree(1);
  TempDir dir("octree_missing");
  const std::string missing = dir.file("nowhere");
  for (const auto& [name, write] :
       std::map<std::string, void (*)(const TraversabilityOcTree&, const std::string&)>{
           {"map.ot", upd::maps::writeTraversabilityOt},
           {"map.bt", upd::maps::writeOccupancyBt},
           {"colour.ot", upd::maps::writeColourOt}}) {
    const std::string target = missing + "/" + name;
    try {
      write(*tree, target);
      ADD_FAILURE() << "no exception for " << target;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(target), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(dir.listing().empty());
  EXPECT_THROW(upd::maps::readTraversabilityOt(missing + "/map.ot"), std::runtime_error);

  OctreeParams other = fixedParams();
  other.resolution_m = 0.2;
  const Frame f = scene();
  TraversabilityOcTree t(0.1);
  EXPECT_THROW(upd::maps::insertScan(t, f.view(), kSensor, other, FusionParams{}),
               std::invalid_argument);
  OctreeParams bad = fixedParams();
  bad.prob_hit = 0.3;
  try {
    bad.validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("OctreeParams.prob_hit = 0.3"), std::string::npos);
  }
}
