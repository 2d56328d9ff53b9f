// Chunks of a loop dealt to a team so that each thread works through a run of neighbouring
// chunks. The stages write each item's result to its own place; with OpenMP's dynamic schedule
// two threads take neighbouring chunks in turn, so their items (by cell, the points of a cell
// scattered over the cloud) meet on the output's cache lines, and each such line moves between
// the cores. Here the chunks are cut into segments of two threads: the even one takes its
// segment's chunks from the front, the odd one from the back, and they meet once. A thread whose
// segment is done takes from the others' (its own end of each, in turn), so the team stays
// balanced as with the dynamic schedule. One thread takes the chunks in order.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace upd::core::detail {

class ChunkDeal {
 public:
  ChunkDeal() = default;
  /// Items [0, n_items) in chunks of chunk items (fewer than 2^32 chunks) for a team of at
  /// most max_team threads.
  ChunkDeal(std::size_t n_items, std::size_t chunk, int max_team) {
    reset(n_items, chunk, max_team);
  }

  /// Deals anew (outside the team's loop: on one thread, before a barrier).
  void reset(std::size_t n_items, std::size_t chunk, int max_team) {
    n_items_ = n_items, chunk_ = chunk;
    n_segments_ = static_cast<std::size_t>(max_team > 2 ? (max_team + 1) / 2 : 1);
    ends_.reset(new Ends[n_segments_]);
    const std::uint64_t n_chunks = (n_items + chunk - 1) / chunk;
    for (std::size_t s = 0; s < n_segments_; ++s) {
      const std::uint64_t front = n_chunks * s / n_segments_;
      const std::uint64_t back = n_chunks * (s + 1) / n_segments_;
      ends_[s].packed.store(back << 32 | front, std::memory_order_relaxed);
    }
  }

  /// A thread's hand: the items [begin, end) of the next chunk for thread me of the team, or
  /// false when all are dealt.
  class Hand {
   public:
    Hand(ChunkDeal& deal, int me)
        : deal_(deal),
          segment_(static_cast<std::size_t>(me / 2) % deal.n_segments_),
          from_back_(me % 2 == 1) {}
    bool next(std::size_t& begin, std::size_t& end) {
      for (; looked_ < deal_.n_segments_; ++looked_) {
        std::size_t chunk;
        if (deal_.take(segment_, from_back_, chunk)) {
          begin = chunk * deal_.chunk_;
          end = std::min(deal_.n_items_, begin + deal_.chunk_);
          return true;
        }
        segment_ = (segment_ + 1) % deal_.n_segments_;
      }
      return false;
    }

   private:
    ChunkDeal& deal_;
    std::size_t segment_;
    bool from_back_;
    std::size_t looked_ = 0;  // segments found empty
  };

 private:
  struct alignas(64) Ends {
    std::atomic<std::uint64_t> packed;  // the next chunk from the front (low 32 bits), and one
                                        // past the next from the back (high 32 bits)
  };

  bool take(std::size_t segment, bool from_back, std::size_t& chunk) {
    std::atomic<std::uint64_t>& ends = ends_[segment].packed;
    std::uint64_t now = ends.load(std::memory_order_relaxed);
    while (true) {
      const std::uint64_t front = now & 0xffffffffu, back = now >> 32;
      if (front >= back) return false;
      const std::uint64_t next = from_back ? (back - 1) << 32 | front : back << 32 | (front + 1);
      if (ends.compare_exchange_weak(now, next, std::memory_order_relaxed)) {
        chunk = static_cast<std::size_t>(from_back ? back - 1 : front);
        return true;
      }
    }
  }

  std::size_t n_items_ = 0, chunk_ = 1, n_segments_ = 0;
  std::unique_ptr<Ends[]> ends_;
};

}  // namespace upd::core::detail
