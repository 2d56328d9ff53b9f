// Writing a figure: the image encoded as PNG in memory, then written through a temporary file
// renamed into place (no half-written PNG on failure).
#pragma once

#include <mrpt/img/CImage.h>

#include <string>

namespace upd::nav {

/// Throws std::runtime_error naming the file when encoding or writing fails.
void writePngAtomically(const mrpt::img::CImage& image, const std::string& path);

}  // namespace upd::nav
