// Private to libs/learn: a model file's bytes as written and checked before OpenCV parses them.
// A text model (.yml, .yaml, .xml) has a comment after its first line with the CRC-32 and the
// length of the text after it (.json, which has no comments: a member "upd_nav_crc32"); a
// compressed one (.gz) is gzip, whose own CRC-32 and length cover the text too. A model is read
// only as `upd train` wrote it: OpenCV's parser and ml module trust what they read (OpenCV
// 4.6's YAML parser loops forever on some malformed documents, its trees' reader dereferences
// a split's variable it never checked, and a changed digit would load as another model), so a
// file whose checksum is missing or does not match is refused before OpenCV sees it. (The
// checksum finds damage; it is no defence against a file crafted to pass it.)
#pragma once

#include <string>

namespace upd::learn::detail {

/// text with its checksum comment after the first line ("%YAML:1.0", "<?xml ...?>", "{"), for
/// format ".yml", ".yaml", ".xml" or ".json" (a member there).
std::string withChecksum(const std::string& text, const std::string& format);

/// Throws std::runtime_error("damaged: ...") where text has a checksum comment that the text
/// after it does not match (cut short, longer, changed), or a damaged one, and
/// std::runtime_error("no checksum ...") where it has none (made or edited by hand).
void checkChecksum(const std::string& text, const std::string& format);

/// gzip of text.
std::string gzip(const std::string& text);

/// The text of the gzip bytes; throws std::runtime_error("damaged: ...") where they are cut
/// short, fail their CRC, are not gzip, hold more than max_bytes, or have bytes after the end.
std::string gunzip(const std::string& bytes, std::size_t max_bytes);

}  // namespace upd::learn::detail
