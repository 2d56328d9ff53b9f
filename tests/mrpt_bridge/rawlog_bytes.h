// The rawlog pre-check tests' bytes: MRPT's serialization of an object, little-endian values, how
// far the check walks an object, and the damage the reader reports for an object after a comment.
#pragma once

#include "../../libs/mrpt_bridge/src/rawlog_precheck.h"
#include "rawlog_damage.h"
#include "temp_dir.h"

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/serialization/CArchive.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

namespace upd::test {

inline std::string serialized(const mrpt::serialization::CSerializable& o) {
  mrpt::io::CMemoryStream mem;
  mrpt::serialization::archiveFrom(mem) << o;
  const auto* data = static_cast<const char*>(mem.getRawBufferData());
  return std::string(data, data + mem.getTotalBytesCount());
}

// The distinctive sizes below are found in the bytes by value (the payloads are zeros).
inline std::string u32(std::uint32_t v) {
  std::string s(4, '\0');
  for (int i = 0; i < 4; ++i) s[i] = static_cast<char>((v >> (8 * i)) & 0xFF);
  return s;
}

// How many bytes the check walks of the object at the start of bytes (0 when it stops before the
// object's end), its reason into *why.
inline std::size_t walked(const std::string& bytes, std::string* why = nullptr) {
  mrpt::io::CMemoryStream mem;
  mem.assignMemoryNotOwn(bytes.data(), bytes.size());
  mrpt_bridge::detail::LookaheadStream in(mem);
  std::size_t checked = 0;
  const std::string reason = mrpt_bridge::detail::precheckNextObject(in, &checked);
  if (why) *why = reason;
  EXPECT_EQ(in.getPosition(), 0u) << "the check consumed bytes";
  return checked;
}

// The reason RawlogReader gives for a file of a comment and then `object`.
inline std::string damageReason(const TempDir& tmp, const std::string& object, std::size_t* head_size) {
  mrpt::obs::CObservationComment before;
  before.text = "before";
  const std::string head = serialized(before);
  *head_size = head.size();
  std::size_t offset = 0;
  const std::string reason =
      upd::test::damageAtSecondObject(tmp.path() / "damaged.rawlog", head + object, &offset);
  if (reason != "(read)") {
    EXPECT_EQ(offset, head.size());
  }
  return reason;
}

// The reason RawlogReader gives for a file of a comment and then `object` with the bytes at `at`
// replaced by `value`.
inline std::string reasonWith(const TempDir& tmp, const std::string& object, std::size_t at,
                              const std::string& value, std::size_t* head_size) {
  return damageReason(tmp, std::string(object).replace(at, value.size(), value), head_size);
}

}  // namespace upd::test
