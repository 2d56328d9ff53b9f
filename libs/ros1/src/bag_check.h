// The walk of a ROS 1 bag (format 2.0) before rosbag_storage reads it. rosbag trusts the
// lengths and offsets it reads: a message's offset in its chunk and the lengths of the records
// there are used to read memory without a bounds check (a flipped byte ended the process with
// SIGSEGV), and an index record of a connection the bag does not declare is reported through a
// null pointer. The walk reads every record of the index and of every chunk (decompressed when
// it is BZ2 or LZ4) and checks that each length stays inside its record, each offset of the
// index lands on a message record of its chunk, and each connection is declared. It hands the
// messages of the topics asked for to the caller as it meets them, so that a topic read whole
// (the transforms) costs no second decompression of the chunks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>

namespace upd::ros1::detail {

/// Damage found by the walk: what is wrong and at which byte (of the file, or of a chunk's
/// decompressed data, with the chunk's byte).
struct BagDamage : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A message of the bag as its index lists it: its connection's topic and MD5 sum (of its type),
/// its time in the bag, and its serialized data (valid during the call that hands it over).
struct BagMessage {
  const std::string& topic;
  const std::string& md5sum;
  std::uint64_t time_ns = 0;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

/// The walk of the bag at path, in two steps: the index first (what rosbag reads when it opens
/// a bag), then the chunks' data (what its views read).
class BagWalk {
 public:
  /// Reads the bag's header, its index and every chunk's header and index records. Throws
  /// BagDamage when rosbag would trust a damaged length or offset there, and for a bag without
  /// an index (its recording did not end). A file that is not a bag of format 2.0 (another
  /// version, not a bag, not readable) is left to rosbag, which reports it: no chunk.
  explicit BagWalk(const std::string& path);
  ~BagWalk();
  BagWalk(const BagWalk&) = delete;
  BagWalk& operator=(const BagWalk&) = delete;

  /// The times of the bag's first and last message (ns since the epoch; begin > end: none).
  std::uint64_t beginNs() const { return begin_ns_; }
  std::uint64_t endNs() const { return end_ns_; }

  /// Decompresses and checks every chunk's records (throws BagDamage). Each message on one of
  /// topics goes to on_message once its chunk has been checked: chunk by chunk in the file's
  /// order, within a chunk by time (then by position), as rosbag's views order a bag whose
  /// chunks follow each other in time (rosbag record writes them so).
  void checkChunks(const std::set<std::string>& topics = {},
                   const std::function<void(const BagMessage&)>& on_message = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::uint64_t begin_ns_ = UINT64_MAX, end_ns_ = 0;
};

}  // namespace upd::ros1::detail
