// One cloud reader on arbitrary bytes, through readCloud (so the content sniffing runs too):
// any input must give a cloud or a std::runtime_error, never a crash, a hang or a sanitizer
// report. The reader is chosen by UPD_FUZZ_EXT (.pcd, .ply, .xyz, .bin).
#include "fuzz_input.h"

#include "upd/io/cloud_io.h"

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = upd::fuzz::inputPath(UPD_FUZZ_EXT);
  upd::fuzz::writeInput(path, data, size);
  try {
    const upd::core::PointCloud c = upd::io::readCloud(path);
    if (c.y.size() != c.size() || c.z.size() != c.size()) __builtin_trap();
    if (c.hasColor() && (c.g.size() != c.size() || c.b.size() != c.size())) __builtin_trap();
    if (c.isOrganized() && c.width * c.height != c.size()) __builtin_trap();
  } catch (const std::runtime_error&) {
    // a refused file: what the reader must do with a bad one
  }
  return 0;
}
