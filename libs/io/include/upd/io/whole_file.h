// A whole input file into memory, for the readers that check its bytes before a library parses
// them (depth PNGs, calibration YAMLs, classifier models).
#pragma once

#include <cstdint>
#include <string>

namespace upd::io {

/// The bytes of the regular file at path, at most max_bytes of them. Throws std::runtime_error
/// whose what() is the reason alone ("not found", "unreadable", "larger than N bytes"): the
/// caller names the file in its own words.
std::string readWholeFile(const std::string& path, std::uintmax_t max_bytes);

}  // namespace upd::io
