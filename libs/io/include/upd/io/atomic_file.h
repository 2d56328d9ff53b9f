// Atomic file output: a reader (another process, a viewer, the next pipeline stage) sees either
// the previous complete file or the new complete file, never a half-written one.
//
// The content is written to a temporary file in the target's directory
// (`<name>.tmp-<pid>-<random>`, same file system so the rename is atomic), checked for stream
// errors after the final flush (a full disk shows up there), and then renamed over the target.
// On any error the temporary file is removed, the target is left untouched, and a
// std::runtime_error naming the file is thrown. Every writer of upd_io goes through here.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace upd::io {

/// Writes path atomically: write() fills a binary-mode stream; whatever it throws propagates
/// after the temporary file has been removed. Throws std::runtime_error when the output
/// directory does not exist (naming it), when the temporary file cannot be created, when the
/// stream fails (e.g. disk full) or when the rename fails.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// The same for writers that open a file by name themselves (MRPT's gzip streams, GDAL):
/// write() gets the temporary file's path (ending in `suffix`, for writers that choose the
/// format by extension), must have closed it when it returns, and is renamed over path.
void writeFileAtomicallyVia(const std::string& path,
                            const std::function<void(const std::string& tmp_path)>& write,
                            const std::string& suffix = "");

}  // namespace upd::io
