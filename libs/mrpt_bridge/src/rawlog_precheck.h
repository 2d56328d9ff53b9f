// Checks of the serialized fields that MRPT 2.5 acts on while it deserializes an object, made on
// the bytes ahead in the stream before MRPT reads them (private to the bridge).
//
// MRPT trusts the sizes it reads. CActionRobotMovement2D rebuilds its pose distribution inside
// its deserialization: with any motion model but the Gaussian one it draws as many particles as
// the stream says, so a corrupt count of 10^9 keeps a playback busy for minutes and gigabytes
// before the object ends. CActionCollection resizes its list of actions to the count it reads.
// precheckNextObject() reads those fields of the next top-level object (a CActionCollection and
// the CActionRobotMovement2D actions in it, or a bare CActionRobotMovement2D) as MRPT 2.5.8
// lays them out (CArchive's object header: a length byte with its high bit set, the class name,
// a version byte; the body; the end flag 0x88), and names what is impossible. Bytes that follow
// another layout are left to MRPT, which reports what it finds.
#pragma once

#include <mrpt/io/CStream.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace upd::mrpt_bridge::detail {

/// Most particles a CActionRobotMovement2D may ask MRPT to draw (MRPT's default is 300; a
/// particle costs ~40 bytes and a few Gaussian draws: 10^5 take milliseconds).
constexpr std::uint32_t kMaxOdometryParticles = 100000;
/// Most actions in one CActionCollection (a robot writes one or two per step).
constexpr std::uint32_t kMaxActionsPerCollection = 4096;

/// A read-only stream over another that can look at the bytes ahead of its position without
/// consuming them. Its position is the count of bytes consumed (the underlying stream's
/// position less the bytes looked at and not yet read).
class LookaheadStream : public mrpt::io::CStream {
 public:
  explicit LookaheadStream(mrpt::io::CStream& in) : in_(in) {}

  size_t Read(void* buffer, size_t count) override;
  /// Throws: the stream is read-only.
  size_t Write(const void* buffer, size_t count) override;
  /// Throws: the stream reads forward only.
  uint64_t Seek(int64_t offset, TSeekOrigin origin = sFromBeginning) override;
  uint64_t getTotalBytesCount() const override;
  uint64_t getPosition() const override;

  /// Copies count bytes, starting offset bytes after the position, into out; false when the
  /// stream ends before them.
  bool peek(std::size_t offset, void* out, std::size_t count);

 private:
  mrpt::io::CStream& in_;
  std::vector<std::uint8_t> ahead_;  ///< bytes read from in_, not consumed from head_ on
  std::size_t head_ = 0;
};

/// Why the next top-level object must not be handed to MRPT ("corrupt CActionRobotMovement2D
/// (action 1 of 1 in a CActionCollection): ..."), or "" when nothing impossible was found.
/// Consumes nothing.
std::string precheckNextObject(LookaheadStream& in);

}  // namespace upd::mrpt_bridge::detail
