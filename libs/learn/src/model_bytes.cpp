#include "model_bytes.h"

#include <zlib.h>

#include <algorithm>
#include <climits>
#include <cstdio>
#include <stdexcept>

namespace upd::learn::detail {

namespace {

std::runtime_error damaged(const std::string& why) { return std::runtime_error("damaged: " + why); }

// The comment around the checksum, by format: before the 8 hex digits, and after them.
bool commentOf(const std::string& format, std::string& open, std::string& close) {
  if (format == ".yml" || format == ".yaml") {
    open = "# upd-nav crc32 ", close = "\n";
  } else if (format == ".xml") {
    open = "<!-- upd-nav crc32 ", close = " -->\n";
  } else if (format == ".json") {  // (no comments in JSON: a member OpenCV reads and we ignore)
    open = "    \"upd_nav_crc32\": \"", close = "\",\n";
  } else {
    return false;
  }
  return true;
}

std::string hex8(unsigned long v) {
  char s[9];
  std::snprintf(s, sizeof s, "%08lx", v & 0xfffffffful);
  return s;
}

unsigned long crcOf(const std::string& text, std::size_t n) {
  unsigned long crc = crc32(0L, Z_NULL, 0);
  const auto* p = reinterpret_cast<const Bytef*>(text.data());
  for (std::size_t at = 0; at < n;) {  // (crc32 takes a 32-bit length)
    const auto step = static_cast<uInt>(std::min<std::size_t>(n - at, 1u << 30));
    crc = crc32(crc, p + at, step);
    at += step;
  }
  return crc;
}

}  // namespace

std::string withChecksum(const std::string& text, const std::string& format) {
  std::string open, close;
  const std::size_t eol = text.find('\n');
  if (!commentOf(format, open, close) || eol == std::string::npos) return text;
  const std::string rest = text.substr(eol + 1);
  return text.substr(0, eol + 1) + open + hex8(crcOf(rest, rest.size())) + " of " +
         std::to_string(rest.size()) + " bytes" + close + rest;
}

void checkChecksum(const std::string& text, const std::string& format) {
  std::string open, close;
  const std::size_t eol = text.find('\n');
  if (!commentOf(format, open, close) || eol == std::string::npos ||
      text.compare(eol + 1, open.size(), open) != 0) {
    throw std::runtime_error(
        std::string("no checksum ") + (format == ".json" ? "member" : "line") +
        " after its first line: a model is read only as `upd train` wrote it (OpenCV's reader "
        "trusts a model's structure: a model made or edited by hand can hang or crash it)");
  }
  // "<open>XXXXXXXX of N bytes<close>", then the N bytes it covers.
  const std::size_t at = eol + 1 + open.size();
  const std::size_t end = text.find(close, at);
  const std::string line = text.substr(at, end == std::string::npos ? 40 : end - at);
  char crc[9] = {};
  unsigned long long n = 0;
  int used = 0;
  if (end == std::string::npos ||
      std::sscanf(line.c_str(), "%8[0-9a-f] of %llu bytes%n", crc, &n, &used) != 2 ||
      used != static_cast<int>(line.size()) || std::string(crc).size() != 8) {
    throw damaged("its checksum line ('" + line.substr(0, 40) + "') is not as written");
  }
  const std::size_t from = end + close.size(), have = text.size() - from;
  if (have != n) {
    throw damaged(have < n ? "cut short: " + std::to_string(have) + " of its " +
                                 std::to_string(n) + " bytes"
                           : std::to_string(have - n) + " bytes more than were written");
  }
  const std::string actual = hex8(crcOf(text.substr(from), have));
  if (actual != crc) {
    throw damaged("its text does not match its checksum (crc32 " + actual +
                  ", written " + crc + "): changed since it was written");
  }
}

std::string gzip(const std::string& text) {
  if (text.size() > UINT_MAX / 2) throw std::runtime_error("gzip: more than 2 GB of text");
  z_stream z{};
  if (deflateInit2(&z, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
    throw std::runtime_error("gzip: cannot start zlib");
  }
  std::string out(deflateBound(&z, text.size()) + 64, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  z.avail_in = static_cast<uInt>(text.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const int r = deflate(&z, Z_FINISH);
  const std::size_t n = z.total_out;
  deflateEnd(&z);
  if (r != Z_STREAM_END) throw std::runtime_error("gzip: zlib could not compress");
  out.resize(n);
  return out;
}

std::string gunzip(const std::string& bytes, std::size_t max_bytes) {
  if (bytes.size() > UINT_MAX) throw damaged("more than 4 GB compressed");
  z_stream z{};
  if (inflateInit2(&z, 15 + 16) != Z_OK) throw std::runtime_error("gunzip: cannot start zlib");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  z.avail_in = static_cast<uInt>(bytes.size());
  std::string out;
  char buf[1 << 16];
  int r = Z_OK;
  while (r == Z_OK) {
    z.next_out = reinterpret_cast<Bytef*>(buf);
    z.avail_out = sizeof buf;
    r = inflate(&z, Z_NO_FLUSH);
    out.append(buf, sizeof buf - z.avail_out);
    if (out.size() > max_bytes) {
      inflateEnd(&z);
      throw damaged("more than " + std::to_string(max_bytes) + " bytes uncompressed");
    }
  }
  const std::string why = z.msg ? z.msg : "";
  const std::size_t left = z.avail_in;
  inflateEnd(&z);
  // (Z_BUF_ERROR: no progress possible, the input used up before the stream's end)
  if (r == Z_BUF_ERROR) throw damaged("cut short (the compressed stream ends before its end mark)");
  if (r != Z_STREAM_END) throw damaged("not valid gzip (" + (why.empty() ? "zlib error" : why) + ")");
  if (left != 0) throw damaged(std::to_string(left) + " bytes after the end of the compressed data");
  return out;
}

}  // namespace upd::learn::detail
