// PLY: a small reader for the three standard encodings (ascii, binary little- and big-endian).
//
// The reader is our own (not PCL's) because it must skip any property and element exactly,
// report truncation instead of returning fewer points, and never print.
#include "upd/io/cloud_io.h"

#include "io_detail.h"
#include "ply_detail.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace upd::io {

namespace {

using detail::fileError;

enum class PlyType : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;  ///< the item type for a list
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;

  bool fixedSize() const {
    return std::none_of(properties.begin(), properties.end(),
                        [](const PlyProperty& p) { return p.is_list; });
  }
};

struct PlyHeader {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  std::uint64_t lines = 0;  ///< header lines, so ascii data errors can give file line numbers
  Eigen::Vector3f sensor_origin = Eigen::Vector3f::Zero();  ///< `comment sensor_origin X Y Z`
};

bool parseType(const std::string& s, PlyType& t) {
  static const struct {
    const char* name;
    PlyType type;
  } kTypes[] = {{"char", PlyType::Int8},     {"int8", PlyType::Int8},
                {"uchar", PlyType::UInt8},   {"uint8", PlyType::UInt8},
                {"short", PlyType::Int16},   {"int16", PlyType::Int16},
                {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},
                {"int", PlyType::Int32},     {"int32", PlyType::Int32},
                {"uint", PlyType::UInt32},   {"uint32", PlyType::UInt32},
                {"float", PlyType::Float32}, {"float32", PlyType::Float32},
                {"double", PlyType::Float64}, {"float64", PlyType::Float64}};
  for (const auto& k : kTypes) {
    if (s == k.name) {
      t = k.type;
      return true;
    }
  }
  return false;
}

std::size_t typeSize(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8: return 1;
    case PlyType::Int16:
    case PlyType::UInt16: return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 0;
}

bool isFloatType(PlyType t) { return t == PlyType::Float32 || t == PlyType::Float64; }

/// One binary value; swap when the file's byte order is not the host's.
double decode(const unsigned char* p, PlyType t, bool swap) {
  unsigned char b[8];
  const std::size_t n = typeSize(t);
  std::memcpy(b, p, n);
  if (swap) detail::reverseBytes(b, n);
  auto load = [&b](auto v) {
    std::memcpy(&v, b, sizeof v);
    return static_cast<double>(v);
  };
  switch (t) {
    case PlyType::Int8: return load(std::int8_t{});
    case PlyType::UInt8: return load(std::uint8_t{});
    case PlyType::Int16: return load(std::int16_t{});
    case PlyType::UInt16: return load(std::uint16_t{});
    case PlyType::Int32: return load(std::int32_t{});
    case PlyType::UInt32: return load(std::uint32_t{});
    case PlyType::Float32: return load(float{});
    case PlyType::Float64: return load(double{});
  }
  return 0.0;
}

std::uint8_t toColor(double v, PlyType t) {
  if (t == PlyType::UInt8) return static_cast<std::uint8_t>(v);
  // Some writers store colour as float in 0..1; integer types wider than a byte are clamped.
  if (isFloatType(t)) v *= 255.0;
  if (!(v > 0.0)) return 0;  // also maps NaN to 0
  if (v >= 255.0) return 255;
  return static_cast<std::uint8_t>(std::lround(v));
}

std::vector<std::string> splitWords(const std::string& line) {
  std::istringstream is(line);
  std::vector<std::string> words;
  for (std::string w; is >> w;) words.push_back(w);
  return words;
}

float parseOriginWord(const std::string& path, const std::string& where, const std::string& s) {
  char* end = nullptr;
  const float v = std::strtof(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !std::isfinite(v)) {
    throw fileError(path, where + "bad sensor_origin coordinate '" + s + "'");
  }
  return v;
}

PlyHeader readHeader(const std::string& path, std::ifstream& in) {
  PlyHeader h;
  std::string line;
  auto next = [&]() -> bool {
    if (!std::getline(in, line)) return false;
    ++h.lines;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    // A last line without its newline: the file was cut inside the header.
    if (in.eof() && line != "end_header") return false;
    return true;
  };
  if (!next() || line != "ply") throw fileError(path, "not a PLY file (no 'ply' magic line)");
  bool have_format = false;
  // A header is a few hundred bytes; a binary file without end_header must not be slurped.
  constexpr std::uint64_t kMaxHeaderLines = 10000;
  while (true) {
    if (!next()) {
      throw fileError(path, "PLY header has no end_header line (truncated or not a PLY file)");
    }
    if (h.lines > kMaxHeaderLines) throw fileError(path, "PLY header has no end_header line");
    const std::string where = "PLY header line " + std::to_string(h.lines) + ": ";
    const std::vector<std::string> w = splitWords(line);
    if (w.empty()) continue;
    if (w[0] == "end_header") break;
    if (w.size() == 5 && w[0] == "comment" && w[1] == "sensor_origin") {
      for (int k = 0; k < 3; ++k) h.sensor_origin[k] = parseOriginWord(path, where, w[2 + k]);
      continue;
    }
    if (w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "format") {
      if (w.size() != 3) throw fileError(path, where + "malformed format line");
      if (w[1] == "ascii") {
        h.format = PlyFormat::Ascii;
      } else if (w[1] == "binary_little_endian") {
        h.format = PlyFormat::BinaryLittleEndian;
      } else if (w[1] == "binary_big_endian") {
        h.format = PlyFormat::BinaryBigEndian;
      } else {
        throw fileError(path, where + "unknown format '" + w[1] + "'");
      }
      if (w[2] != "1.0") throw fileError(path, where + "unsupported PLY version " + w[2]);
      have_format = true;
    } else if (w[0] == "element") {
      if (w.size() != 3) throw fileError(path, where + "malformed element line");
      PlyElement e;
      e.name = w[1];
      const auto* first = w[2].data();
      const auto* last = first + w[2].size();
      const auto r = std::from_chars(first, last, e.count);
      if (r.ec != std::errc() || r.ptr != last) {
        throw fileError(path, where + "bad element count '" + w[2] + "'");
      }
      h.elements.push_back(e);
    } else if (w[0] == "property") {
      if (h.elements.empty()) throw fileError(path, where + "property before any element");
      PlyProperty p;
      if (w.size() == 5 && w[1] == "list") {
        p.is_list = true;
        if (!parseType(w[2], p.count_type) || isFloatType(p.count_type)) {
          throw fileError(path, where + "bad list count type '" + w[2] + "'");
        }
        if (!parseType(w[3], p.type)) throw fileError(path, where + "unknown type '" + w[3] + "'");
        p.name = w[4];
      } else if (w.size() == 3) {
        if (!parseType(w[1], p.type)) throw fileError(path, where + "unknown type '" + w[1] + "'");
        p.name = w[2];
      } else {
        throw fileError(path, where + "malformed property line");
      }
      h.elements.back().properties.push_back(p);
    } else {
      throw fileError(path, where + "unknown keyword '" + w[0] + "'");
    }
  }
  if (!have_format) throw fileError(path, "PLY header has no format line");
  return h;
}

/// Where the vertex properties we use sit in an element's property list (-1: absent), the
/// requested extra properties (any scalar type, read as float) among them.
struct VertexLayout {
  int x = -1, y = -1, z = -1, r = -1, g = -1, b = -1;
  std::vector<int> extra;

  VertexLayout(const PlyElement& e, const std::vector<std::string>& extra_names)
      : extra(extra_names.size(), -1) {
    for (int i = 0; i < static_cast<int>(e.properties.size()); ++i) {
      const PlyProperty& p = e.properties[i];
      if (p.is_list) continue;
      if (p.name == "x") x = i;
      else if (p.name == "y") y = i;
      else if (p.name == "z") z = i;
      else if (p.name == "red") r = i;
      else if (p.name == "green") g = i;
      else if (p.name == "blue") b = i;
      for (std::size_t k = 0; k < extra_names.size(); ++k) {
        if (p.name == extra_names[k]) extra[k] = i;
      }
    }
  }
  bool hasXyz() const { return x >= 0 && y >= 0 && z >= 0; }
  bool hasColor() const { return r >= 0 && g >= 0 && b >= 0; }
};

// Appends one vertex whose property values (in the element's order) are v.
void appendVertex(const std::vector<double>& v, const PlyElement& e, const VertexLayout& lay,
                  bool color, detail::PlyVertices& out) {
  core::PointCloud& cloud = out.cloud;
  cloud.x.push_back(static_cast<float>(v[lay.x]));
  cloud.y.push_back(static_cast<float>(v[lay.y]));
  cloud.z.push_back(static_cast<float>(v[lay.z]));
  if (color) {
    cloud.r.push_back(toColor(v[lay.r], e.properties[lay.r].type));
    cloud.g.push_back(toColor(v[lay.g], e.properties[lay.g].type));
    cloud.b.push_back(toColor(v[lay.b], e.properties[lay.b].type));
  }
  for (std::size_t k = 0; k < lay.extra.size(); ++k) {
    if (lay.extra[k] >= 0) out.extra[k].push_back(static_cast<float>(v[lay.extra[k]]));
  }
}

void prepareVertices(detail::PlyVertices& out, const VertexLayout& lay, std::size_t n,
                     bool color) {
  out.cloud.resize(n, color);
  out.cloud.width = n;
  out.cloud.height = 1;
  for (std::size_t k = 0; k < lay.extra.size(); ++k) {
    if (lay.extra[k] >= 0) out.extra[k].resize(n);
  }
}

void setUnorganized(core::PointCloud& cloud) {
  cloud.width = cloud.x.size();
  cloud.height = 1;
}

// ---- binary ----

class BinaryReader {
 public:
  BinaryReader(const std::string& path, std::ifstream& in, bool swap)
      : path_(path), in_(in), swap_(swap) {}

  void read(unsigned char* dst, std::size_t n, const std::string& what) {
    in_.read(reinterpret_cast<char*>(dst), static_cast<std::streamsize>(n));
    if (static_cast<std::size_t>(in_.gcount()) != n) {
      throw fileError(path_, "truncated PLY: the file ends inside " + what);
    }
  }
  double value(PlyType t, const std::string& what) {
    unsigned char b[8];
    read(b, typeSize(t), what);
    return decode(b, t, swap_);
  }
  void skip(std::uint64_t n, const std::string& what) {
    unsigned char buf[4096];
    while (n > 0) {
      const std::size_t k = static_cast<std::size_t>(std::min<std::uint64_t>(n, sizeof buf));
      read(buf, k, what);
      n -= k;
    }
  }
  /// A list's length, checked so a corrupt count cannot make us skip gigabytes silently.
  std::uint64_t listCount(PlyType t, const std::string& what) {
    const double c = value(t, what);
    if (!(c >= 0.0)) throw fileError(path_, "corrupt PLY: negative list length in " + what);
    return static_cast<std::uint64_t>(c);
  }
  bool swap() const { return swap_; }

 private:
  const std::string& path_;
  std::ifstream& in_;
  bool swap_;
};

std::string instanceName(const PlyElement& e, std::uint64_t i) {
  return e.name + " " + std::to_string(i) + " of " + std::to_string(e.count);
}

void skipBinaryElement(BinaryReader& rd, const PlyElement& e) {
  if (e.fixedSize()) {
    std::uint64_t stride = 0;
    for (const auto& p : e.properties) stride += typeSize(p.type);
    rd.skip(stride * e.count, "element '" + e.name + "'");
    return;
  }
  for (std::uint64_t i = 0; i < e.count; ++i) {
    for (const auto& p : e.properties) {
      if (p.is_list) {
        const std::uint64_t c = rd.listCount(p.count_type, instanceName(e, i));
        rd.skip(c * typeSize(p.type), instanceName(e, i));
      } else {
        rd.skip(typeSize(p.type), instanceName(e, i));
      }
    }
  }
}

void readBinaryVertices(const std::string& path, std::ifstream& in, BinaryReader& rd,
                        const PlyElement& e, const VertexLayout& lay, detail::PlyVertices& out) {
  const bool color = lay.hasColor();
  const std::size_t np = e.properties.size();
  if (e.fixedSize()) {
    std::vector<std::size_t> offset(np);
    std::size_t stride = 0;
    for (std::size_t i = 0; i < np; ++i) {
      offset[i] = stride;
      stride += typeSize(e.properties[i].type);
    }
    // Check the declared count against what the file holds before allocating for it.
    const std::uint64_t avail = detail::bytesLeft(in);
    if (stride > 0 && e.count > avail / stride) {
      throw fileError(path, "truncated PLY: the header declares " + std::to_string(e.count) +
                                " vertices of " + std::to_string(stride) + " bytes but only " +
                                std::to_string(avail) + " bytes of data follow");
    }
    const std::size_t n = static_cast<std::size_t>(e.count);
    prepareVertices(out, lay, n, color);
    core::PointCloud& cloud = out.cloud;
    const auto& P = e.properties;
    const bool swap = rd.swap();
    constexpr std::size_t kChunk = 1 << 16;
    std::vector<unsigned char> buf(kChunk * stride);
    for (std::size_t first = 0; first < n; first += kChunk) {
      const std::size_t m = std::min(kChunk, n - first);
      rd.read(buf.data(), m * stride, "the vertex data");
      for (std::size_t j = 0; j < m; ++j) {
        const unsigned char* rec = buf.data() + j * stride;
        const std::size_t i = first + j;
        cloud.x[i] = static_cast<float>(decode(rec + offset[lay.x], P[lay.x].type, swap));
        cloud.y[i] = static_cast<float>(decode(rec + offset[lay.y], P[lay.y].type, swap));
        cloud.z[i] = static_cast<float>(decode(rec + offset[lay.z], P[lay.z].type, swap));
        if (color) {
          cloud.r[i] = toColor(decode(rec + offset[lay.r], P[lay.r].type, swap), P[lay.r].type);
          cloud.g[i] = toColor(decode(rec + offset[lay.g], P[lay.g].type, swap), P[lay.g].type);
          cloud.b[i] = toColor(decode(rec + offset[lay.b], P[lay.b].type, swap), P[lay.b].type);
        }
        for (std::size_t k = 0; k < lay.extra.size(); ++k) {
          const int p = lay.extra[k];
          if (p < 0) continue;
          out.extra[k][i] = static_cast<float>(decode(rec + offset[p], P[p].type, swap));
        }
      }
    }
    return;
  }
  // Vertex records with list properties (rare): property by property. No up-front size check is
  // possible, so grow as we read and let a truncated file fail on the read.
  std::vector<double> v(np, 0.0);
  for (std::uint64_t i = 0; i < e.count; ++i) {
    for (std::size_t k = 0; k < np; ++k) {
      const PlyProperty& p = e.properties[k];
      if (p.is_list) {
        const std::uint64_t c = rd.listCount(p.count_type, instanceName(e, i));
        rd.skip(c * typeSize(p.type), instanceName(e, i));
      } else {
        v[k] = rd.value(p.type, instanceName(e, i));
      }
    }
    appendVertex(v, e, lay, color, out);
  }
  setUnorganized(out.cloud);
}

// ---- ascii ----

bool parseNumber(const std::string& token, double& v) {
  const char* first = token.data();
  const char* last = first + token.size();
  if (first != last && *first == '+') ++first;  // from_chars rejects a leading '+'
  const auto r = std::from_chars(first, last, v);
  return r.ec == std::errc() && r.ptr == last;
}

class AsciiReader {
 public:
  AsciiReader(const std::string& path, std::ifstream& in, std::uint64_t header_lines)
      : path_(path), in_(in), line_no_(header_lines) {}

  /// The next non-blank line split into words; throws when the file ends before `what`.
  const std::vector<std::string>& nextLine(const std::string& what) {
    std::string line;
    while (std::getline(in_, line)) {
      ++line_no_;
      words_ = splitWords(line);
      if (!words_.empty()) return words_;
    }
    throw fileError(path_, "truncated PLY: the file ends after line " + std::to_string(line_no_) +
                               ", before " + what);
  }
  std::string where() const { return "line " + std::to_string(line_no_) + ": "; }
  std::uint64_t lineNumber() const { return line_no_; }

 private:
  const std::string& path_;
  std::ifstream& in_;
  std::uint64_t line_no_;
  std::vector<std::string> words_;
};

void readAsciiVertices(const std::string& path, AsciiReader& rd, const PlyElement& e,
                       const VertexLayout& lay, detail::PlyVertices& out) {
  const bool color = lay.hasColor();
  const std::size_t np = e.properties.size();
  std::vector<double> v(np, 0.0);
  // Reserve only what a plausible file could hold: the count may be corrupt.
  out.cloud.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(e.count, 1u << 20)));
  for (std::uint64_t i = 0; i < e.count; ++i) {
    const auto& w = rd.nextLine(instanceName(e, i));
    std::size_t t = 0;
    auto number = [&](const char* what) {
      if (t >= w.size()) {
        throw fileError(path, rd.where() + "too few values for " + instanceName(e, i));
      }
      double d;
      if (!parseNumber(w[t], d)) {
        throw fileError(path, rd.where() + "'" + w[t] + "' is not a number (" + what + ")");
      }
      ++t;
      return d;
    };
    for (std::size_t k = 0; k < np; ++k) {
      const PlyProperty& p = e.properties[k];
      if (p.is_list) {
        const double c = number("list length");
        if (!(c >= 0.0) || c != std::floor(c)) {
          throw fileError(path, rd.where() + "bad list length for " + instanceName(e, i));
        }
        for (std::uint64_t j = 0; j < static_cast<std::uint64_t>(c); ++j) number("list item");
      } else {
        v[k] = number(p.name.c_str());
      }
    }
    if (t != w.size()) {
      throw fileError(path, rd.where() + "more values than the " + std::to_string(np) +
                                " properties of element '" + e.name + "'");
    }
    appendVertex(v, e, lay, color, out);
  }
  setUnorganized(out.cloud);
}

// Opens path into in and reads its header: the stream is left at the first element's data.
PlyHeader openHeader(const std::string& path, std::ifstream& in) {
  detail::requireReadableFile(path);
  in.open(path, std::ios::binary);
  if (!in) throw fileError(path, "cannot open for reading");
  return readHeader(path, in);
}

const PlyElement& vertexElement(const std::string& path, const PlyHeader& h) {
  const auto vertex = std::find_if(h.elements.begin(), h.elements.end(),
                                   [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex == h.elements.end()) throw fileError(path, "PLY has no vertex element");
  return *vertex;
}

}  // namespace

namespace detail {

PlyVertices readPlyVertices(const std::string& path, const std::vector<std::string>& extra) {
  std::ifstream in;
  const PlyHeader h = openHeader(path, in);
  const PlyElement& vertex = vertexElement(path, h);
  const VertexLayout lay(vertex, extra);
  if (!lay.hasXyz()) throw fileError(path, "PLY vertex element has no x/y/z properties");

  PlyVertices out;
  out.cloud.sensor_origin = h.sensor_origin;
  out.extra.resize(extra.size());
  for (std::size_t k = 0; k < extra.size(); ++k) out.has_extra.push_back(lay.extra[k] >= 0);
  if (h.format == PlyFormat::Ascii) {
    AsciiReader rd(path, in, h.lines);
    for (const PlyElement* e = h.elements.data(); e != &vertex; ++e) {
      for (std::uint64_t i = 0; i < e->count; ++i) rd.nextLine(instanceName(*e, i));
    }
    readAsciiVertices(path, rd, vertex, lay, out);
  } else {
    const bool file_le = h.format == PlyFormat::BinaryLittleEndian;
    BinaryReader rd(path, in, file_le != detail::kHostIsLittleEndian);
    for (const PlyElement* e = h.elements.data(); e != &vertex; ++e) skipBinaryElement(rd, *e);
    readBinaryVertices(path, in, rd, vertex, lay, out);
  }
  // Elements after the vertices (faces) are not needed: a point cloud is the vertices.
  return out;
}

}  // namespace detail

core::PointCloud readPly(const std::string& path) {
  return detail::readPlyVertices(path, {}).cloud;
}

std::vector<std::string> plyVertexProperties(const std::string& path) {
  std::ifstream in;
  const PlyHeader h = openHeader(path, in);
  std::vector<std::string> names;
  for (const PlyProperty& p : vertexElement(path, h).properties) {
    names.push_back(p.name);
  }
  return names;
}

}  // namespace upd::io
