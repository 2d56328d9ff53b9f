// The release of UPD-Nav this library was built from (the CMake project's version), for
// `upd --version`, bug reports and the files the project writes (PLY header, summary.json).
#pragma once

namespace upd::core {

/// "MAJOR.MINOR.PATCH" of the libraries loaded at run time.
const char* version();

}  // namespace upd::core
