// A ROS 1 bag on arbitrary bytes, read as `upd playback RUN.bag` reads it: the walk of the bag,
// then rosbag, every transform, camera info, depth image and point cloud converted. Any input
// must end cleanly or in one std::runtime_error (anything else escapes: a finding).
#include "fuzz_input.h"

#include "upd/ros1/bag_reader.h"

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = upd::fuzz::inputPath(".bag");
  upd::fuzz::writeInput(path, data, size);
  try {
    upd::ros1::readBag(path, {}, [](const upd::ros1::BagFrame&) {});
  } catch (const std::runtime_error&) {
    // damage: what the reader reports
  }
  return 0;
}
