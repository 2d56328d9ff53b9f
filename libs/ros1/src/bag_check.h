// The walk of a ROS 1 bag (format 2.0) before rosbag_storage reads it. rosbag trusts the
// lengths and offsets it reads: a message's offset in its chunk and the lengths of the records
// there are used to read memory without a bounds check (a flipped byte ended the process with
// SIGSEGV), and an index record of a connection the bag does not declare is reported through a
// null pointer. The walk reads every record of the index and of every chunk (decompressed when
// it is BZ2 or LZ4) and checks that each length stays inside its record, each offset of the
// index lands on a message record of its chunk, and each connection is declared.
#pragma once

#include <stdexcept>
#include <string>

namespace upd::ros1::detail {

/// Damage found by the walk: what is wrong and at which byte (of the file, or of a chunk's
/// decompressed data, with the chunk's byte).
struct BagDamage : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Walks the bag at path. Throws BagDamage when rosbag would trust a damaged length or offset,
/// and for a bag without an index (its recording did not end). A file that is not a bag of
/// format 2.0 (another version, not a bag, not readable) is left to rosbag, which reports it.
void checkBag(const std::string& path);

}  // namespace upd::ros1::detail
