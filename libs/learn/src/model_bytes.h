// Private to libs/learn: a model file's bytes as written and checked before OpenCV parses them.
// A text model (.yml, .yaml, .xml) has a comment after its first line with the CRC-32 and the
// length of the text after it (.json, which has no comments: a member "upd_nav_crc32"); a compressed one (.gz) is gzip, whose own CRC-32 and length cover
// the text too. A file whose check
// fails is damage, refused before OpenCV's parser sees it (OpenCV 4.6's YAML parser can loop
// forever on a damaged document, and a changed digit would load as another model).
#pragma once

#include <string>

namespace upd::learn::detail {

/// text with its checksum comment after the first line ("%YAML:1.0", "<?xml ...?>", "{"), for
/// format ".yml", ".yaml", ".xml" or ".json" (a member there).
std::string withChecksum(const std::string& text, const std::string& format);

/// Throws std::runtime_error("damaged: ...") where text has a checksum comment that the text
/// after it does not match (cut short, longer, changed), or a damaged one; text without one
/// (written by hand) passes.
void checkChecksum(const std::string& text, const std::string& format);

/// gzip of text.
std::string gzip(const std::string& text);

/// The text of the gzip bytes; throws std::runtime_error("damaged: ...") where they are cut
/// short, fail their CRC, are not gzip, hold more than max_bytes, or have bytes after the end.
std::string gunzip(const std::string& bytes, std::size_t max_bytes);

}  // namespace upd::learn::detail
