// The lengths inside a bag message's data, checked before roscpp deserializes it: roscpp
// resizes a string or an array to the length it reads, then finds the data short, so a damaged
// length asks for up to 4 GB per field (an array of transforms: 4 G elements).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace upd::ros1::detail {

/// Whether every string and array length in the serialized message stays inside its size bytes,
/// walked by the layout of the types the bag reader instantiates: sensor_msgs/Image,
/// sensor_msgs/CompressedImage, sensor_msgs/CameraInfo, sensor_msgs/PointCloud2 and
/// tf2_msgs/TFMessage. Other types: true.
bool lengthsFit(const std::string& datatype, const std::uint8_t* data, std::size_t size);

}  // namespace upd::ros1::detail
