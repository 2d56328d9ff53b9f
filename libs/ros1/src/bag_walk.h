// The reader of a ROS 1 bag (format 2.0). A bag's lengths and offsets are not trusted (rosbag's
// own reader reads a message at the offset its index gives, and the record lengths there, without
// a bounds check: a flipped byte ended the process with SIGSEGV). The walk reads every record of
// the index and of every chunk (decompressed when it is BZ2 or LZ4, as rosbag decompresses it) and
// checks that each length stays inside its record, each offset of the index lands on a message
// record of its chunk, and each connection is declared; then the messages are read from the
// checked chunks in the order of their times, as rosbag's views give them. The walk hands the
// messages of the topics asked for to the caller as it checks them, so that a topic read whole
// before the others (the transforms) costs no decompression of its own, and keeps the chunks it
// decompressed (up to a memory budget) for the reads after it.
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

/// Why a file is no bag at all (unreadable, or no bag's version line).
struct NotABag : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A message of the bag as its index lists it: its connection's topic, type and MD5 sum (the
/// type is read by its MD5 sum, as rosbag's isType does; the name is for messages), its time in
/// the bag, and its serialized data (valid during the call that hands it over).
struct BagMessage {
  const std::string& topic;
  const std::string& datatype;
  const std::string& md5sum;
  std::uint64_t time_ns = 0;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

/// The walk of the bag at path, in two steps: the index first, then the chunks' data; then its
/// messages read from the checked chunks.
class BagWalk {
 public:
  /// The decompressed bytes of the chunks decompressed at a time (one chunk at least).
  static constexpr std::uint64_t kBatchBytes = 64u << 20;

  /// The compressed chunks' decompressed bytes that checkChunks keeps for the reads after it:
  /// 512 MiB, or an eighth of the machine's memory where that is less.
  static std::uint64_t defaultKeepBytes();

  /// Reads the bag's header, its index and every chunk's header and index records. Throws
  /// NotABag for a file that cannot be read or has no bag's version line; BagDamage for a bag
  /// of another format than 2.0, one without an index (its recording did not end), and a damaged
  /// length or offset. checkChunks keeps the compressed chunks it checks decompressed, in the
  /// file's order up to keep_bytes of their data, so that readMessages does not decompress them
  /// again.
  explicit BagWalk(const std::string& path, std::uint64_t keep_bytes = defaultKeepBytes());
  ~BagWalk();
  BagWalk(const BagWalk&) = delete;
  BagWalk& operator=(const BagWalk&) = delete;

  /// The times of the bag's first and last message (ns since the epoch; begin > end: none).
  std::uint64_t beginNs() const { return begin_ns_; }
  std::uint64_t endNs() const { return end_ns_; }
  /// Whether the index lists a message on topic.
  bool hasMessages(const std::string& topic) const;

  /// Decompresses and checks every chunk's records (throws BagDamage), the compressed chunks
  /// kBatchBytes of them at a time on every core. Each message on one of topics goes to
  /// on_message once its chunk has been checked: chunk by chunk in the file's order, within a
  /// chunk by time (then by position), as rosbag's views order a bag whose chunks follow each
  /// other in time (rosbag record writes them so).
  void checkChunks(const std::set<std::string>& topics = {},
                   const std::function<void(const BagMessage&)>& on_message = {});

  /// After checkChunks: every message on topics to on_message in the order of their times in the
  /// bag (then of their chunks and positions) until on_message returns false, the compressed
  /// chunks decompressed batch_bytes of them at a time (one at least) on every core.
  void readMessages(const std::set<std::string>& topics,
                    const std::function<bool(const BagMessage&)>& on_message,
                    std::uint64_t batch_bytes = kBatchBytes);

  /// The compressed chunks decompressed so far (a chunk as often as it was decompressed).
  std::size_t decompressions() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::uint64_t begin_ns_ = UINT64_MAX, end_ns_ = 0;
};

}  // namespace upd::ros1::detail
