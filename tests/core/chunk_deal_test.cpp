// ChunkDeal on teams of 1-3 threads, dealt for up to 5: every item is dealt once, in whole
// chunks; one thread takes them in order; of two, the first takes a run from the front and the
// second a run from the back, so that they meet once; a team smaller than the deal was cut for
// still takes every item.
#include "../../libs/core/src/chunk_deal.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <utility>
#include <vector>

#include "upd/core/openmp.h"

namespace upd::core {
namespace {

using Ranges = std::vector<std::pair<std::size_t, std::size_t>>;

// The ranges each thread of a team of `threads` took, in its order, from a deal cut for
// max_team.
std::vector<Ranges> deal(std::size_t n_items, std::size_t chunk, int max_team, int threads) {
  detail::ChunkDeal d(n_items, chunk, max_team);
  std::vector<Ranges> taken(static_cast<std::size_t>(threads));
#pragma omp parallel num_threads(threads)
  {
    const int me = openmp::threadIndex();
    detail::ChunkDeal::Hand hand(d, me);
    for (std::size_t b, e; hand.next(b, e);) taken[static_cast<std::size_t>(me)].push_back({b, e});
  }
  return taken;
}

// (Teams of up to 3 threads, deals cut for up to 5: LLVM's OpenMP runtime, under the sanitizer
// build, leaks a thread's state when a team grows beyond the CPUs and shrinks again.)
TEST(ChunkDeal, EveryItemIsDealtOnceInWholeChunks) {
  for (const std::size_t n : {0u, 1u, 15u, 16u, 17u, 1000u, 6822u}) {
    for (const auto& [threads, max_team] : {std::pair{1, 1}, {2, 2}, {3, 3}, {2, 5}, {3, 5}}) {
      const auto taken = deal(n, 16, max_team, threads);
      std::vector<int> times(n, 0);
      for (const Ranges& r : taken) {
        for (const auto& [b, e] : r) {
          EXPECT_EQ(b % 16, 0u) << "a chunk starts at a multiple of the chunk size";
          EXPECT_EQ(e, std::min(n, b + 16)) << "a chunk is whole (the last one may be short)";
          for (std::size_t i = b; i < e; ++i) ++times[i];
        }
      }
      for (std::size_t i = 0; i < n; ++i) {
        ASSERT_EQ(times[i], 1) << "item " << i << " of " << n << " on " << threads
                               << " threads, dealt for " << max_team;
      }
    }
  }
}

TEST(ChunkDeal, OneThreadTakesTheChunksInOrder) {
  const auto taken = deal(100, 8, 4, 1);  // (cut for four threads: two segments)
  std::size_t next = 0;
  for (const auto& [b, e] : taken[0]) {
    EXPECT_EQ(b, next);
    next = e;
  }
  EXPECT_EQ(next, 100u);
}

// Whether the ranges, in the order taken, run on without a gap: forward (each begins where the
// one before ended) or backward (each ends where the one before began).
bool runsOn(const Ranges& r, bool forward) {
  for (std::size_t j = 1; j < r.size(); ++j) {
    if (forward ? r[j].first != r[j - 1].second : r[j].second != r[j - 1].first) return false;
  }
  return true;
}

TEST(ChunkDeal, TwoThreadsMeetOnce) {
  for (int round = 0; round < 20; ++round) {
    const auto taken = deal(6822, 16, 2, 2);
    EXPECT_TRUE(runsOn(taken[0], true)) << "the first thread takes a run from the front";
    EXPECT_TRUE(runsOn(taken[1], false)) << "the second takes a run from the back";
    if (!taken[0].empty()) {
      EXPECT_EQ(taken[0].front().first, 0u);
    }
    if (!taken[1].empty()) {
      EXPECT_EQ(taken[1].front().second, 6822u);
    }
  }
}

TEST(ChunkDeal, ATeamSmallerThanTheDealTakesEveryItem) {
  const auto taken = deal(1000, 16, 6, 2);  // (three segments, two threads)
  std::size_t items = 0;
  for (const Ranges& r : taken) {
    for (const auto& [b, e] : r) items += e - b;
  }
  EXPECT_EQ(items, 1000u);
}

}  // namespace
}  // namespace upd::core
