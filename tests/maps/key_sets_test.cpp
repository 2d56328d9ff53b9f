// The key sets of the octree insert (libs/maps/src/key_sets.h) against std::set references:
// each key listed once, in the order first added, across the growth of their tables.
#include <gtest/gtest.h>

#include <octomap/OcTreeKey.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "../../libs/maps/src/key_sets.h"

namespace {

using octomap::OcTreeKey;
using Tuple = std::tuple<int, int, int>;

Tuple tupleOf(const OcTreeKey& k) { return {k[0], k[1], k[2]}; }

// Keys along rays from one voxel, as a frame's rays give them: many repeats, runs within a
// brick of 4 x 4 x 4 voxels, bricks on both sides of key 32768 and at the key range's ends.
std::vector<OcTreeKey> rayKeys(int rays, int length) {
  std::vector<OcTreeKey> keys;
  const int origins[][3] = {{32768, 32768, 32768}, {3, 65530, 32766}, {65533, 1, 2}};
  for (int r = 0; r < rays; ++r) {
    const int* o = origins[r % 3];
    for (int s = 0; s < length; ++s) {
      const int dx = (r * 7 % 5) - 2, dy = (r * 3 % 5) - 2, dz = r % 2;
      const auto at = [&](int base, int d) {
        return static_cast<octomap::key_type>(std::clamp(base + d * s / 2, 0, 65535));
      };
      keys.emplace_back(at(o[0], dx), at(o[1], dy), at(o[2], dz));
    }
  }
  return keys;
}

TEST(KeySets, VoxelMarksListEachVoxelOnceInOrderAndNeverAnOccupiedOneFree) {
  const std::vector<OcTreeKey> free_keys = rayKeys(300, 120);
  std::vector<OcTreeKey> occupied_keys;
  // (among the first rays' voxels only, so that the free ones add bricks and grow the table)
  for (std::size_t i = 0; i < free_keys.size() / 10; i += 37) occupied_keys.push_back(free_keys[i]);
  occupied_keys.push_back(occupied_keys.front());  // (a repeat)

  upd::maps::detail::VoxelMarks marks;
  marks.clear(1);  // (so that it grows many times)
  for (const auto& k : occupied_keys) marks.markOccupied(k);
  for (int pass = 0; pass < 2; ++pass) {  // (the second after every growth of the table)
    for (const auto& k : free_keys) marks.markFree(k);
  }

  std::set<Tuple> seen;
  std::vector<Tuple> occupied, free;
  for (const auto& k : occupied_keys) {
    if (seen.insert(tupleOf(k)).second) occupied.push_back(tupleOf(k));
  }
  for (const auto& k : free_keys) {
    if (seen.insert(tupleOf(k)).second) free.push_back(tupleOf(k));
  }
  std::vector<Tuple> got_occupied, got_free;
  for (const auto& k : marks.occupied()) got_occupied.push_back(tupleOf(k));
  for (const auto& k : marks.free()) got_free.push_back(tupleOf(k));
  ASSERT_GT(free.size(), 1000u);
  EXPECT_EQ(got_occupied, occupied);
  EXPECT_EQ(got_free, free);

  marks.clear(1);  // reused: nothing of the last frame is left
  marks.markFree(free_keys.front());
  EXPECT_TRUE(marks.occupied().empty());
  EXPECT_EQ(marks.free().size(), 1u);
}

TEST(KeySets, FlatKeySetGivesEachKeyItsPlaceInTheList) {
  const std::vector<OcTreeKey> keys = rayKeys(100, 60);
  upd::maps::detail::FlatKeySet set;
  set.clear(0);
  std::vector<Tuple> first;
  std::set<Tuple> seen;
  for (const auto& k : keys) {
    const auto [index, added] = set.insert(k);
    EXPECT_EQ(added, seen.insert(tupleOf(k)).second);
    if (added) first.push_back(tupleOf(k));
    ASSERT_LT(index, set.keys().size());
    EXPECT_EQ(tupleOf(set.keys()[index]), tupleOf(k));
  }
  std::vector<Tuple> listed;
  for (const auto& k : set.keys()) listed.push_back(tupleOf(k));
  EXPECT_EQ(listed, first);
}

TEST(KeySets, RadixSortOfMortonCodesIsStdSortsOrder) {
  std::mt19937_64 rng(7);
  for (const int bits : {48, 49}) {
    const std::uint64_t top = std::uint64_t{1} << (bits - 1);  // (a 49th bit: the fifth digit)
    for (const std::uint64_t high : {std::uint64_t{0}, std::uint64_t{0xABC} << 36, top}) {
      for (const std::uint64_t mask :
           {top - 1 + top, std::uint64_t{0xFFFFFF}, std::uint64_t{0xFFF000FFF}}) {
        std::vector<std::uint64_t> codes(5000);
        for (auto& c : codes) c = high | (rng() & mask);  // (digits all share, and some not)
        codes.push_back(codes[17]);                       // (a repeat)
        std::vector<std::uint64_t> expected = codes, buffer;
        std::sort(expected.begin(), expected.end());
        upd::maps::detail::radixSort(codes, buffer, bits);
        EXPECT_EQ(codes, expected) << bits << " " << std::hex << high << " " << mask;
      }
    }
  }
}

}  // namespace
