#include "bag_messages.h"

#include <cstring>

namespace upd::ros1::detail {

namespace {

// A cursor over the serialized data (ROS 1: little-endian, a uint32 length before each string
// and variable-length array); ok() turns false for good at the first read past the end.
class Walk {
 public:
  Walk(const std::uint8_t* data, std::size_t size) : data_(data), left_(size) {}
  bool ok() const { return ok_; }
  void skip(std::uint64_t n) {
    if (!ok_ || n > left_) {
      ok_ = false;
      return;
    }
    data_ += n;
    left_ -= n;
  }
  std::uint32_t u32() {
    std::uint32_t v = 0;
    if (ok_ && left_ >= 4) std::memcpy(&v, data_, 4);
    skip(4);
    return ok_ ? v : 0;
  }
  void string() { skip(u32()); }
  void array(std::uint64_t element_bytes) { skip(element_bytes * u32()); }
  // An array of n elements, each walked by `element` (which takes at least one byte).
  template <class F>
  void elements(F element) {
    for (std::uint32_t n = u32(); ok_ && n > 0; --n) element();
  }
  void header() {
    skip(12);  // seq, stamp
    string();  // frame_id
  }

 private:
  const std::uint8_t* data_;
  std::size_t left_;
  bool ok_ = true;
};

}  // namespace

bool lengthsFit(const std::string& datatype, const std::uint8_t* data, std::size_t size) {
  Walk w(data, size);
  if (datatype == "sensor_msgs/Image") {
    w.header();
    w.skip(8);  // height, width
    w.string();  // encoding
    w.skip(5);  // is_bigendian, step
    w.array(1);  // data
  } else if (datatype == "sensor_msgs/CompressedImage") {
    w.header();
    w.string();  // format
    w.array(1);  // data
  } else if (datatype == "sensor_msgs/CameraInfo") {
    w.header();
    w.skip(8);  // height, width
    w.string();  // distortion_model
    w.array(8);  // D
    w.skip(8 * (9 + 9 + 12) + 8 + 17);  // K, R, P; binning; roi
  } else if (datatype == "sensor_msgs/PointCloud2") {
    w.header();
    w.skip(8);  // height, width
    w.elements([&] {  // fields: name, offset, datatype, count
      w.string();
      w.skip(9);
    });
    w.skip(9);  // is_bigendian, point_step, row_step
    w.array(1);  // data
    w.skip(1);  // is_dense
  } else if (datatype == "tf2_msgs/TFMessage") {
    w.elements([&] {  // transforms: header, child_frame_id, translation and rotation
      w.header();
      w.string();
      w.skip(7 * 8);
    });
  }
  return w.ok();
}

}  // namespace upd::ros1::detail
