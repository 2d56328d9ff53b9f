// PCD through PCL's untyped reader (pcl::PCLPointCloud2): the file's own fields are read by
// their offsets, so no PCL point type (and none of its template instantiations) is involved.
#include "upd/io/atomic_file.h"
#include "upd/io/cloud_io.h"

#include "io_detail.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <ostream>
#include <vector>

namespace upd::io {

namespace {

using detail::fileError;

/// PCL prints its own errors to stderr; a library must not print, so PCL is silenced while we
/// call it and its failures are reported through our exceptions instead. PCL's verbosity is
/// one process-wide setting: concurrent loads may leave it silenced, never louder.
class QuietPclConsole {
 public:
  QuietPclConsole() : saved_(pcl::console::getVerbosityLevel()) {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  }
  ~QuietPclConsole() { pcl::console::setVerbosityLevel(saved_); }
  QuietPclConsole(const QuietPclConsole&) = delete;
  QuietPclConsole& operator=(const QuietPclConsole&) = delete;

 private:
  pcl::console::VERBOSITY_LEVEL saved_;
};

const pcl::PCLPointField* findField(const pcl::PCLPointCloud2& blob, const char* name) {
  for (const auto& f : blob.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

std::string fieldNames(const pcl::PCLPointCloud2& blob) {
  std::string s;
  for (const auto& f : blob.fields) s += (s.empty() ? "" : " ") + f.name;
  return s.empty() ? "none" : s;
}

bool isNumericType(std::uint8_t t) {
  return t >= pcl::PCLPointField::INT8 && t <= pcl::PCLPointField::FLOAT64;
}

/// Value of one numeric field (PCL stores the data in host byte order).
float readAsFloat(const std::uint8_t* p, std::uint8_t datatype) {
  auto load = [p](auto v) {
    std::memcpy(&v, p, sizeof v);
    return static_cast<float>(v);
  };
  switch (datatype) {
    case pcl::PCLPointField::INT8: return load(std::int8_t{});
    case pcl::PCLPointField::UINT8: return load(std::uint8_t{});
    case pcl::PCLPointField::INT16: return load(std::int16_t{});
    case pcl::PCLPointField::UINT16: return load(std::uint16_t{});
    case pcl::PCLPointField::INT32: return load(std::int32_t{});
    case pcl::PCLPointField::UINT32: return load(std::uint32_t{});
    case pcl::PCLPointField::FLOAT32: return load(float{});
    case pcl::PCLPointField::FLOAT64: return load(double{});
    default: return 0.f;  // unreachable: callers check isNumericType
  }
}

/// Checks that the data section the header promises is really in the file before PCL reads
/// it: PCL maps the file into memory, and reading past the end of a truncated file would crash
/// the process (SIGBUS) instead of failing.
void requireCompleteBody(const std::string& path, const pcl::PCLPointCloud2& header,
                         int data_type, unsigned int data_idx) {
  const std::uintmax_t file_size = std::filesystem::file_size(path);
  const std::uintmax_t points = std::uintmax_t{header.width} * header.height;
  if (data_type == 1) {  // binary
    const std::uintmax_t need = data_idx + points * header.point_step;
    if (file_size < need) {
      throw fileError(path, "truncated PCD: DATA binary needs " + std::to_string(need) +
                                " bytes for " + std::to_string(points) + " points, the file has " +
                                std::to_string(file_size));
    }
  } else if (data_type == 2) {  // binary_compressed: two uint32 sizes, then the LZF block
    if (file_size < std::uintmax_t{data_idx} + 8) {
      throw fileError(path, "truncated PCD: the binary_compressed block header is missing");
    }
    std::ifstream in(path, std::ios::binary);
    in.seekg(data_idx);
    unsigned char sizes[8];
    if (!in.read(reinterpret_cast<char*>(sizes), 8)) {
      throw fileError(path, "cannot read the binary_compressed block header");
    }
    std::uint32_t compressed = 0, uncompressed = 0;
    for (int i = 3; i >= 0; --i) compressed = (compressed << 8) | sizes[i];  // little-endian
    for (int i = 7; i >= 4; --i) uncompressed = (uncompressed << 8) | sizes[i];
    // PCL allocates the uncompressed size before it decompresses: a corrupt one must not make
    // it allocate gigabytes. The fields hold at most points * point_step bytes, and LZF expands
    // a block at most 88 times (a 3-byte back-reference copies up to 264 bytes).
    // And PCL copies every field of every point out of the block: it must hold them all.
    std::uintmax_t field_bytes = 0;
    for (const auto& f : header.fields) {
      field_bytes += static_cast<std::uintmax_t>(pcl::getFieldSize(f.datatype)) * f.count;
    }
    const std::uintmax_t fields = points * header.point_step;
    if (uncompressed > fields || uncompressed < points * field_bytes ||
        uncompressed > std::uintmax_t{compressed} * 88 + 64) {
      throw fileError(path, "corrupt PCD: the binary_compressed block says " +
                                std::to_string(uncompressed) + " bytes uncompressed from " +
                                std::to_string(compressed) + ", the header's " +
                                std::to_string(points) + " points hold " + std::to_string(fields));
    }
    const std::uintmax_t need = std::uintmax_t{data_idx} + 8 + compressed;
    if (file_size < need) {
      throw fileError(path, "truncated PCD: the binary_compressed block needs " +
                                std::to_string(need) + " bytes, the file has " +
                                std::to_string(file_size));
    }
  }
}

/// PCL's ascii parser reads a malformed number as 0 without a word; check every value of
/// the body first so a damaged ascii file fails instead of giving wrong points.
void requireValidAsciiBody(const std::string& path, const pcl::PCLPointCloud2& header,
                           unsigned int data_idx) {
  std::size_t per_point = 0;
  for (const auto& f : header.fields) per_point += f.count;
  const std::size_t points = std::size_t{header.width} * header.height;

  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::size_t line_no = 0;
  // Count the header's lines so errors give the line number in the file.
  std::size_t consumed = 0;
  while (consumed < data_idx && std::getline(in, line)) {
    ++line_no;
    consumed += line.size() + 1;
  }
  std::size_t seen = 0;
  while (seen < points && std::getline(in, line)) {
    ++line_no;
    std::size_t values = 0;
    std::size_t pos = 0;
    while (true) {
      pos = line.find_first_not_of(" \t\r", pos);
      if (pos == std::string::npos) break;
      const std::size_t end = std::min(line.find_first_of(" \t\r", pos), line.size());
      const char* first = line.data() + pos;
      const char* last = line.data() + end;
      if (first != last && *first == '+') ++first;  // from_chars rejects a leading '+'
      double v;
      const auto r = std::from_chars(first, last, v);
      if (r.ec != std::errc() || r.ptr != last) {
        throw fileError(path, "line " + std::to_string(line_no) + ": '" +
                                  line.substr(pos, std::min<std::size_t>(end - pos, 40)) +
                                  "' is not a number");
      }
      ++values;
      pos = end;
    }
    if (values == 0) continue;
    if (values != per_point) {
      throw fileError(path, "line " + std::to_string(line_no) + ": " + std::to_string(values) +
                                " values, the FIELDS/COUNT header says " +
                                std::to_string(per_point));
    }
    ++seen;
  }
  if (seen < points) {
    throw fileError(path, "truncated PCD: " + std::to_string(seen) + " of " +
                              std::to_string(points) + " points in the DATA ascii section");
  }
}

// The unsigned integers after a header line's keyword (at most 64 of them); false when one is
// not a number.
bool headerNumbers(const std::string& line, std::size_t from, std::vector<std::uint64_t>& out) {
  out.clear();
  std::size_t pos = from;
  while (out.size() < 64) {
    pos = line.find_first_not_of(" \t\r", pos);
    if (pos == std::string::npos) return true;
    const std::size_t end = std::min(line.find_first_of(" \t\r", pos), line.size());
    std::uint64_t v = 0;
    const auto r = std::from_chars(line.data() + pos, line.data() + end, v);
    if (r.ec != std::errc() || r.ptr != line.data() + end) return false;
    out.push_back(v);
    pos = end;
  }
  return true;
}

/// A header line's keyword as PCL's readHeader finds it: the line's first word (after white
/// space, as an istream's >> reads it), matched by its first letters ("POINTSX 9" is a POINTS
/// line to PCL); the words after it begin at `after`.
struct HeaderWord {
  std::string first;
  std::size_t after = 0;
  bool is(const char* keyword) const { return first.compare(0, std::strlen(keyword), keyword) == 0; }
};

bool isSpace(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

/// At most n bytes of a header line from `from`, for a message: a byte that is not printable
/// ASCII (a corrupt file's binary) shown as '?', so that the message stays one line of text.
std::string quoted(const std::string& line, std::size_t from, std::size_t n) {
  std::string q = line.substr(std::min(from, line.size()), n);
  for (char& c : q) {
    if (c < 0x20 || c > 0x7e) c = '?';
  }
  return "'" + q + "'";
}

HeaderWord headerWord(const std::string& line) {
  std::size_t b = 0;
  while (b < line.size() && isSpace(line[b])) ++b;
  std::size_t e = b;
  while (e < line.size() && !isSpace(line[e])) ++e;
  return {line.substr(b, e - b), e};
}

/// The count after a header line's keyword as PCL reads it (an istream's >> into an unsigned
/// integer: white space, a sign, digits, the rest ignored; "-1" wraps to the largest value, and
/// so does a number past the range), or nothing where no digit follows.
std::optional<std::uint64_t> streamCount(const std::string& line, std::size_t from) {
  const char* p = line.c_str() + from;  // (strtoull skips the white space itself)
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(p, &end, 10);
  if (end == p) return std::nullopt;
  return errno == ERANGE ? std::numeric_limits<std::uint64_t>::max() : static_cast<std::uint64_t>(v);
}

/// What a header asks PCL to allocate, line by line as PCL reads it: each POINTS line resizes the
/// data to POINTS x the point's bytes at that line (FIELDS sets 4 bytes a field, SIZE and COUNT
/// change them), so the largest count and the largest point size seen bound it. updateStep after
/// every FIELDS, SIZE and COUNT line keeps that largest point size.
struct HeaderClaims {
  std::vector<std::uint64_t> sizes, counts;
  std::size_t fields = 0;
  std::uint64_t points = 0, width = 0, height = 1, step = 0;
  void updateStep() {
    std::uint64_t now = 0;
    for (std::size_t f = 0; f < std::max(fields, sizes.size()); ++f) {
      now += (f < sizes.size() ? sizes[f] : 4) * (f < counts.size() ? counts[f] : 1);
    }
    step = std::max(step, now);
  }
};

/// A SIZE or COUNT line checked (each field's SIZE is 1, 2, 4 or 8 bytes and its COUNT at least
/// 1: PCL reads them as ints and sums SIZE x COUNT as unsigned, a "-4" becomes 4 GB a point).
void checkSizeOrCount(const std::string& path, const std::string& line, const HeaderWord& w,
                      HeaderClaims& claims) {
  const bool size = w.is("SIZE");
  std::vector<std::uint64_t>& list = size ? claims.sizes : claims.counts;
  const bool ok = headerNumbers(line, w.after, list) &&
                  std::all_of(list.begin(), list.end(), [&](std::uint64_t v) {
                    return size ? (v == 1 || v == 2 || v == 4 || v == 8) : (v >= 1 && v <= 1u << 20);
                  });
  if (!ok) {
    throw fileError(path, "corrupt PCD header: " + quoted(line, w.after - w.first.size(), 80) + " (" +
                              (size ? "a SIZE is 1, 2, 4 or 8 bytes" : "a COUNT is at least 1") +
                              ")");
  }
}

/// The bytes PCL would allocate: the larger of POINTS and WIDTH x HEIGHT, times the point's
/// bytes, in long double so that no product wraps. A file holds at most its size in binary, and
/// about 90 times it compressed (LZF's longest back-reference: 264 bytes from 3).
void checkClaims(const std::string& path, const HeaderClaims& c) {
  const long double claimed =
      std::max<long double>(c.points, static_cast<long double>(c.width) * c.height) *
      std::max<std::uint64_t>(c.step, 1);
  std::error_code ec;
  const auto file_bytes = std::filesystem::file_size(path, ec);
  const long double bound = 128.0L * (ec ? 0 : file_bytes) + 65536.0L;
  if (claimed > bound) {
    throw fileError(path, "corrupt PCD header: POINTS " + std::to_string(c.points) + " (WIDTH " +
                              std::to_string(c.width) + " x HEIGHT " + std::to_string(c.height) +
                              ") of " + std::to_string(c.step) +
                              " bytes each, more than a file of " +
                              std::to_string(ec ? 0 : file_bytes) + " bytes can hold");
  }
}

/// One header line into claims, as PCL's readHeader reads it; false when its first word is none
/// of the header's keywords (PCL's header ends there).
bool readHeaderLine(const std::string& path, const std::string& line, const HeaderWord& w,
                    HeaderClaims& claims) {
  if (w.is("FIELDS") || w.is("COLUMNS")) {
    claims.fields = 0;  // (its words after the keyword, split at spaces, tabs and CRs, as PCL)
    for (std::size_t p = w.after; (p = line.find_first_not_of(" \t\r", p)) != std::string::npos;
         p = line.find_first_of(" \t\r", p)) {
      ++claims.fields;
    }
    claims.updateStep();
  } else if (w.is("SIZE") || w.is("COUNT")) {
    checkSizeOrCount(path, line, w, claims);
    claims.updateStep();
  } else if (w.is("POINTS") || w.is("WIDTH") || w.is("HEIGHT")) {
    const std::optional<std::uint64_t> v = streamCount(line, w.after);
    if (!v) return true;
    if (w.is("POINTS")) claims.points = std::max(claims.points, *v);
    // (WIDTH and HEIGHT are 32-bit in PCL: a larger number reads as the largest.)
    const std::uint64_t v32 = std::min<std::uint64_t>(*v, 0xFFFFFFFFu);
    if (w.is("WIDTH")) claims.width = v32;
    if (w.is("HEIGHT")) claims.height = v32;
  } else if (!w.is("VERSION") && !w.is("TYPE") && !w.is("VIEWPOINT") && !w.is("DATA")) {
    return false;
  }
  return true;
}

/// The header, checked where PCL would act on it: a header cut off before its DATA line (PCL
/// takes such a file as a cloud of no points, or reads the header's own lines as ascii data), a
/// line before it that is no header line (where PCL's header ends), and a point count whose
/// bytes this file cannot hold (PCL's readHeader allocates POINTS x the point's bytes before it
/// reads the body: a corrupt count asks for terabytes). PCL reads header lines on after the DATA
/// line too, up to the first line that is not one (the body's first line, as a rule), and so
/// does this check.
void checkHeaderLines(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::size_t n = 0;
  constexpr std::size_t kMaxHeaderLines = 1000;  // a PCD header has about a dozen
  HeaderClaims claims;
  bool data = false;
  while (std::getline(in, line)) {
    if (++n > kMaxHeaderLines) {
      throw fileError(path, data ? "corrupt PCD header: header lines go on after its DATA line "
                                   "past line " + std::to_string(kMaxHeaderLines)
                                 : "truncated or invalid PCD header: no DATA line in its first " +
                                       std::to_string(kMaxHeaderLines) + " lines");
    }
    const HeaderWord w = headerWord(line);
    if (w.first.empty() || w.first[0] == '#') continue;
    if (!readHeaderLine(path, line, w, claims)) {
      if (data) break;
      throw fileError(path, "corrupt PCD header: line " + std::to_string(n) + " (" +
                                quoted(line, 0, 40) + ") is not a header line, before the DATA line");
    }
    data = data || w.is("DATA");
  }
  if (n == 0) throw fileError(path, "empty file, not a PCD file (no header)");
  if (!data) {
    throw fileError(path, "truncated or invalid PCD header: no DATA line in its first " +
                              std::to_string(n) + " lines");
  }
  checkClaims(path, claims);
}

// Reads and checks the header, and checks the body against it before PCL parses the body (PCL
// itself reads past a truncated one). Throws naming path.
void checkPcdFile(const std::string& path, pcl::PCDReader& reader) {
  checkHeaderLines(path);
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
  int version = 0;
  int data_type = 0;
  unsigned int data_idx = 0;
  int rc = -1;
  try {
    rc = reader.readHeader(path, blob, origin, orientation, version, data_type, data_idx);
  } catch (const std::exception& e) {
    throw fileError(path, std::string("invalid PCD header: ") + e.what());
  }
  if (rc < 0) throw fileError(path, "invalid PCD header (not a PCD file, or a corrupt header)");

  if (blob.fields.empty()) throw fileError(path, "not a PCD file (no FIELDS in the header)");
  const pcl::PCLPointField* fx = findField(blob, "x");
  const pcl::PCLPointField* fy = findField(blob, "y");
  const pcl::PCLPointField* fz = findField(blob, "z");
  if (!fx || !fy || !fz) {
    throw fileError(path, "has no x/y/z fields (fields: " + fieldNames(blob) +
                              "), so it is not a point cloud");
  }
  for (const pcl::PCLPointField* f : {fx, fy, fz}) {
    if (!isNumericType(f->datatype)) {
      throw fileError(path, "field '" + f->name + "' has an unsupported type");
    }
  }
  requireCompleteBody(path, blob, data_type, data_idx);
  if (data_type == 0) requireValidAsciiBody(path, blob, data_idx);
}

// The cloud of a read blob: x, y, z (any numeric type) and the packed colour when there is one.
core::PointCloud cloudFromBlob(const std::string& path, const pcl::PCLPointCloud2& blob) {
  const std::size_t n = std::size_t{blob.width} * blob.height;
  // The body may carry different field offsets than the header said (PCL re-derives them);
  // look them up again.
  const pcl::PCLPointField* fx = findField(blob, "x");
  const pcl::PCLPointField* fy = findField(blob, "y");
  const pcl::PCLPointField* fz = findField(blob, "z");
  if (!fx || !fy || !fz) throw fileError(path, "has no x/y/z fields after reading");

  // rgb is a float whose bits are the packed colour, rgba a uint32: either way the 4 bytes are
  // 0xAARRGGBB in host order. A colour field of another size is not a colour we know; it is
  // ignored rather than misread.
  const pcl::PCLPointField* fc = findField(blob, "rgb");
  if (!fc) fc = findField(blob, "rgba");
  if (fc && pcl::getFieldSize(fc->datatype) != 4) fc = nullptr;

  // Every field read must lie within the point's bytes (a corrupt header can say otherwise).
  for (const pcl::PCLPointField* f : {fx, fy, fz, fc}) {
    if (f && std::uintmax_t{f->offset} + pcl::getFieldSize(f->datatype) > blob.point_step) {
      throw fileError(path, "corrupt PCD: field '" + f->name + "' at byte " +
                                std::to_string(f->offset) + " lies outside the point's " +
                                std::to_string(blob.point_step) + " bytes");
    }
  }
  core::PointCloud cloud;
  cloud.resize(n, fc != nullptr);
  const std::uint8_t* data = blob.data.data();
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = data + i * blob.point_step;
    cloud.x[i] = readAsFloat(p + fx->offset, fx->datatype);
    cloud.y[i] = readAsFloat(p + fy->offset, fy->datatype);
    cloud.z[i] = readAsFloat(p + fz->offset, fz->datatype);
    if (fc) {
      std::uint32_t c;
      std::memcpy(&c, p + fc->offset, 4);
      cloud.r[i] = static_cast<std::uint8_t>((c >> 16) & 0xff);
      cloud.g[i] = static_cast<std::uint8_t>((c >> 8) & 0xff);
      cloud.b[i] = static_cast<std::uint8_t>(c & 0xff);
    }
  }
  if (blob.height > 1) {
    cloud.width = blob.width;
    cloud.height = blob.height;
  } else {
    cloud.width = n;
    cloud.height = 1;
  }
  return cloud;
}

}  // namespace

core::PointCloud readPcd(const std::string& path) {
  detail::requireReadableFile(path);
  const QuietPclConsole quiet;
  pcl::PCDReader reader;
  checkPcdFile(path, reader);

  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
  int version = 0;
  int rc = -1;
  try {
    rc = reader.read(path, blob, origin, orientation, version);
  } catch (const std::exception& e) {
    throw fileError(path, std::string("corrupt PCD data: ") + e.what());
  }
  const std::size_t n = std::size_t{blob.width} * blob.height;
  if (rc < 0 || blob.data.size() < n * blob.point_step) {
    throw fileError(path, "corrupt or truncated PCD data (" + std::to_string(n) +
                              " points declared)");
  }
  core::PointCloud cloud = cloudFromBlob(path, blob);
  cloud.sensor_origin = origin.head<3>();
  return cloud;
}

void writePcd(const std::string& path, const core::PointCloud& cloud) {
  const std::size_t n = cloud.size();
  if (cloud.y.size() != n || cloud.z.size() != n) {
    throw std::invalid_argument("writePcd: x, y, z of the cloud differ in size");
  }
  const bool color = cloud.hasColor();

  pcl::PCLPointCloud2 blob;
  const char* names[] = {"x", "y", "z", "rgb"};
  const int nfields = color ? 4 : 3;
  for (int i = 0; i < nfields; ++i) {
    pcl::PCLPointField f;
    f.name = names[i];
    f.offset = static_cast<pcl::uindex_t>(4 * i);
    f.datatype = pcl::PCLPointField::FLOAT32;
    f.count = 1;
    blob.fields.push_back(f);
  }
  blob.point_step = static_cast<pcl::uindex_t>(4 * nfields);
  if (cloud.isOrganized()) {
    blob.width = static_cast<pcl::uindex_t>(cloud.width);
    blob.height = static_cast<pcl::uindex_t>(cloud.height);
  } else {
    blob.width = static_cast<pcl::uindex_t>(n);
    blob.height = 1;
  }
  blob.row_step = blob.point_step * blob.width;
  blob.is_dense = false;

  // The header comes from PCL so the file is exactly what PCL expects; the body is the packed
  // records, built here so the whole file goes through writeFileAtomically.
  std::string body;
  body.reserve(n * blob.point_step);
  for (std::size_t i = 0; i < n; ++i) {
    detail::appendLittleEndian(body, cloud.x[i]);
    detail::appendLittleEndian(body, cloud.y[i]);
    detail::appendLittleEndian(body, cloud.z[i]);
    if (color) {
      const std::uint32_t c = (std::uint32_t{cloud.r[i]} << 16) |
                              (std::uint32_t{cloud.g[i]} << 8) | std::uint32_t{cloud.b[i]};
      float packed;
      std::memcpy(&packed, &c, 4);
      detail::appendLittleEndian(body, packed);
    }
  }
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  origin.head<3>() = cloud.sensor_origin;
  // generateHeaderBinary stops after POINTS; the DATA line is the caller's (as in PCL's own
  // PCDWriter::writeBinary).
  const std::string header =
      pcl::PCDWriter().generateHeaderBinary(blob, origin, Eigen::Quaternionf::Identity()) +
      "DATA binary\n";
  writeFileAtomically(path, [&](std::ostream& os) {
    os << header;
    os.write(body.data(), static_cast<std::streamsize>(body.size()));
  });
}

}  // namespace upd::io
