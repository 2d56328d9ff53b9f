// The rawlog damage tests' reading: the damage RawlogReader reports in a rawlog written from
// bytes.
#pragma once

#include "upd/mrpt_bridge/rawlog_reader.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <string>

namespace upd::test {

// bytes written to file and read: the first object read as an entry, then the reason of the
// damage RawlogReader reports at the second (its byte offset into *byte_offset), or "(read)"
// when the file reads to its end.
inline std::string damageAtSecondObject(const std::filesystem::path& file,
                                        const std::string& bytes,
                                        std::size_t* byte_offset = nullptr) {
  std::ofstream(file, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  mrpt_bridge::RawlogReader reader(file.string());
  mrpt_bridge::RawlogEntry e;
  EXPECT_TRUE(reader.next(e));
  try {
    while (reader.next(e)) {
    }
  } catch (const mrpt_bridge::RawlogError& err) {
    EXPECT_EQ(err.objectIndex(), 1u);
    if (byte_offset) *byte_offset = err.byteOffset();
    return err.reason();
  }
  return "(read)";
}

}  // namespace upd::test
