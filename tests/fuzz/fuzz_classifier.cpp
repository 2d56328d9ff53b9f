// A classifier model file on arbitrary bytes, read as YAML (PointClassifier::load: its checksum
// line, then OpenCV's parser and ml module). Any input must give a model or a
// std::runtime_error, never a crash, a hang or a sanitizer report. OpenCV's reader trusts a
// model's structure (regressions/classifier: two texts its parser loops on, and a split of an
// undeclared variable it dereferenced null on), so a model is read only where its checksum
// holds: the fuzzer's changes meet the checksum, and this target checks that nothing else
// gets through to OpenCV.
#include "fuzz_input.h"

#include "upd/learn/classifier.h"

#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string yml = upd::fuzz::inputPath(".yml");
  upd::fuzz::writeInput(yml, data, size);
  try {
    upd::learn::PointClassifier::load(yml);
  } catch (const std::runtime_error&) {
    // a refused file: what the loader must do with a bad one
  }
  return 0;
}
