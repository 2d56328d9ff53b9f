// The first line of a ROS 1 bag ("#ROSBAG V2.0"), read as rosbag_storage reads it, so that a bag
// is what ROS's own tools take for one.
#pragma once

#include <cstdint>
#include <fstream>
#include <string>

namespace upd::ros1::detail {

// The bag's first line as rosbag reads it (fgets of at most 1,023 bytes, then sscanf
// "#ROS%s V%d.%d" into a 100-byte word, the version major * 100 + minor), and the byte after
// that line. found false: it is not a bag's version line.
struct VersionLine {
  bool found = false;
  bool is_2_0 = false;  // the version rosbag reads is 200
  std::string text;     // "MAJOR.MINOR" as written
};

/// The version line of the file in: found false where it is not a bag's version line. after is
/// the byte after that line. Throws BagDamage for a word after "#ROS" of 100 characters or more
/// (rosbag's reader overflows its buffer on it).
VersionLine bagVersion(std::ifstream& in, std::uint64_t& after);

}  // namespace upd::ros1::detail
