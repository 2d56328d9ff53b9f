// One cloud reader on arbitrary bytes, through readCloud (so the content sniffing runs too):
// any input must give a cloud or a std::runtime_error, never a crash, a hang or a sanitizer
// report. The reader is chosen by UPD_FUZZ_EXT (.pcd, .ply, .xyz, .bin); a .ply input is also
// read by readScoredPly.
#include "fuzz_input.h"

#include "upd/io/cloud_io.h"

#include <stdexcept>
#include <string>

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
  if (std::string(UPD_FUZZ_EXT) != ".ply") return 0;
  try {  // the same bytes as a scored PLY: the same parser with extra columns
    const upd::io::ScoredPly s = upd::io::readScoredPly(path);
    const std::size_t n = s.cloud.size();
    for (const auto* v : {&s.nx, &s.ny, &s.nz, &s.rx, &s.ry, &s.rz, &s.zeta, &s.cost}) {
      if (v->size() != n) __builtin_trap();
    }
    if (s.label.size() != n) __builtin_trap();
  } catch (const std::runtime_error&) {
  }
  return 0;
}
