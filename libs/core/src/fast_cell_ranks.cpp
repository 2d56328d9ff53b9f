// The rank table's look-ups of many items at once (fast_cell_ranks.h), in a function of its own
// so that GCC clones it for the running CPU.
#include "fast_cell_ranks.h"

#include "upd/core/vector_clones.h"

namespace upd::core::detail {

UPD_VECTOR_CLONES
void rankedIds(const RankedCells& ranks, const CellRows& rows, std::size_t b, std::size_t e,
               std::uint32_t* cell_of) {
  for (std::size_t i = b; i < e; ++i) {
    if (cell_of[i] == kNoIndex) continue;
    const std::size_t at = i * rows.stride;
    cell_of[i] = ranks.id(ranks.index(rows.x[at], rows.y[at], rows.z[at]));
  }
}

}  // namespace upd::core::detail
