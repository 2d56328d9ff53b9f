#include "bag_walk.h"

#include "bag_version.h"

#include <bzlib.h>
#include <roslz4/lz4s.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

namespace upd::ros1::detail {

namespace {

// Record ops of the format (rosbag/constants.h).
constexpr std::uint8_t kOpMessageData = 0x02;
constexpr std::uint8_t kOpFileHeader = 0x03;
constexpr std::uint8_t kOpIndexData = 0x04;
constexpr std::uint8_t kOpChunk = 0x05;
constexpr std::uint8_t kOpChunkInfo = 0x06;
constexpr std::uint8_t kOpConnection = 0x07;

// A record's header holds a few fields, a connection's its message definition: kilobytes.
constexpr std::uint32_t kMaxHeaderBytes = 1u << 24;
// rosbag closes a chunk at 768 kB by default; a chunk holds at least one whole message.
constexpr std::uint32_t kMaxChunkBytes = 1u << 30;

// A chunk's decompressed data, left uninitialized until the decompressor writes it: a damaged
// chunk that claims up to 1 GB costs the pages written before the damage is found, not 1 GB.
template <class T>
struct Uninitialized : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = Uninitialized<U>;
  };
  Uninitialized() = default;
  template <class U>
  Uninitialized(const Uninitialized<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... A>
  void construct(U* p, A&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<A>(args)...);
  }
};
using ChunkBuffer = std::vector<char, Uninitialized<char>>;

[[noreturn]] void damage(const std::string& what, std::uint64_t byte) {
  throw BagDamage(what + " (byte " + std::to_string(byte) + ")");
}

// Bytes of the file, or of one chunk's data.
class Bytes {
 public:
  virtual ~Bytes() = default;
  virtual std::uint64_t size() const = 0;
  /// The n bytes at pos into out; false when they are not all there.
  virtual bool read(std::uint64_t pos, std::size_t n, char* out) const = 0;
  /// The byte of the file a position stands for (for the messages).
  virtual std::uint64_t fileByte(std::uint64_t pos) const = 0;
  /// The n bytes at pos where they are in memory (null where they are to be read), all there.
  virtual const char* view(std::uint64_t, std::size_t) const { return nullptr; }
};

class FileBytes : public Bytes {
 public:
  FileBytes(std::ifstream& in, std::uint64_t begin, std::uint64_t size)
      : in_(in), begin_(begin), size_(size) {}
  std::uint64_t size() const override { return size_; }
  bool read(std::uint64_t pos, std::size_t n, char* out) const override {
    if (pos > size_ || n > size_ - pos) return false;
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(begin_ + pos));
    return static_cast<bool>(in_.read(out, static_cast<std::streamsize>(n)));
  }
  std::uint64_t fileByte(std::uint64_t pos) const override { return begin_ + pos; }

 private:
  std::ifstream& in_;
  std::uint64_t begin_, size_;
};

class BufferBytes : public Bytes {
 public:
  BufferBytes(const ChunkBuffer& data, std::uint64_t chunk_byte)
      : data_(data), chunk_byte_(chunk_byte) {}
  std::uint64_t size() const override { return data_.size(); }
  bool read(std::uint64_t pos, std::size_t n, char* out) const override {
    if (pos > data_.size() || n > data_.size() - pos) return false;
    std::memcpy(out, data_.data() + pos, n);
    return true;
  }
  std::uint64_t fileByte(std::uint64_t) const override { return chunk_byte_; }
  const char* view(std::uint64_t pos, std::size_t n) const override {
    return pos <= data_.size() && n <= data_.size() - pos ? data_.data() + pos : nullptr;
  }

 private:
  const ChunkBuffer& data_;
  std::uint64_t chunk_byte_;
};

std::uint32_t u32At(const Bytes& b, std::uint64_t pos, const std::string& what) {
  char c[4];
  if (!b.read(pos, 4, c)) damage(what + ": the data ends inside it", b.fileByte(pos));
  std::uint32_t v;
  std::memcpy(&v, c, 4);
  return v;
}

using Fields = std::map<std::string, std::string>;

// A header at pos: its length, then fields "name=value", each after its own length. next is
// the position after it.
Fields headerAt(const Bytes& b, std::uint64_t pos, std::uint64_t& next, const std::string& what) {
  const std::uint32_t len = u32At(b, pos, what);
  if (len > kMaxHeaderBytes || len > b.size() - pos - 4) {
    damage(what + ": a header of " + std::to_string(len) + " bytes runs past the end",
           b.fileByte(pos));
  }
  std::string h(len, '\0');
  b.read(pos + 4, len, h.data());
  Fields fields;
  for (std::size_t i = 0; i < len;) {
    std::uint32_t field_len = 0;
    if (len - i < 4) damage(what + ": a header field's length is cut", b.fileByte(pos));
    std::memcpy(&field_len, h.data() + i, 4);
    i += 4;
    if (field_len > len - i) damage(what + ": a header field runs past its header", b.fileByte(pos));
    const std::string field = h.substr(i, field_len);
    i += field_len;
    const auto eq = field.find('=');
    if (eq == std::string::npos) damage(what + ": a header field without '='", b.fileByte(pos));
    fields[field.substr(0, eq)] = field.substr(eq + 1);
  }
  next = pos + 4 + len;
  return fields;
}

// A numeric field as rosbag reads it: present and exactly its size.
template <class T>
T field(const Fields& f, const char* name, const std::string& what, std::uint64_t byte) {
  const auto it = f.find(name);
  if (it == f.end() || it->second.size() != sizeof(T)) {
    damage(what + ": no " + std::to_string(sizeof(T)) + "-byte field '" + name + "'", byte);
  }
  T v;
  std::memcpy(&v, it->second.data(), sizeof(T));
  return v;
}

struct Record {
  std::uint8_t op = 0;
  Fields fields;
  std::uint64_t data_pos = 0;
  std::uint32_t data_len = 0;
  std::uint64_t end() const { return data_pos + data_len; }
};

// A record at pos (a header, then its data after its length), whose data lies within b.
Record recordAt(const Bytes& b, std::uint64_t pos, const std::string& what) {
  Record r;
  std::uint64_t next = 0;
  r.fields = headerAt(b, pos, next, what);
  r.op = field<std::uint8_t>(r.fields, "op", what, b.fileByte(pos));
  r.data_len = u32At(b, next, what);
  r.data_pos = next + 4;
  if (r.data_len > b.size() - r.data_pos) {
    damage(what + ": its " + std::to_string(r.data_len) + " bytes of data run past the end",
           b.fileByte(next));
  }
  return r;
}

Record recordAt(const Bytes& b, std::uint64_t pos, std::uint8_t op, const std::string& what) {
  Record r = recordAt(b, pos, what);
  if (r.op != op) {
    damage(what + ": a record of op " + std::to_string(r.op) + " where op " + std::to_string(op) +
               " belongs",
           b.fileByte(pos));
  }
  return r;
}

struct ChunkInfo {
  std::uint64_t pos = 0;
  std::size_t connections = 0;  // index records after the chunk
};

// A compressed chunk's data, decompressed as rosbag decompresses it (BZ2 or LZ4) into out (its
// size bytes): false where it does not decompress to exactly that. Safe on several threads at
// once (libbz2 and roslz4 keep no state between calls).
bool decompress(const ChunkBuffer& in, const std::string& compression, std::uint32_t size,
                ChunkBuffer& out) {
  out.resize(size);
  unsigned int out_len = size;
  const bool ok =
      compression == "bz2"
          ? BZ2_bzBuffToBuffDecompress(out.data(), &out_len, const_cast<char*>(in.data()),
                                       static_cast<unsigned int>(in.size()), 0, 0) == BZ_OK
          : roslz4_buffToBuffDecompress(const_cast<char*>(in.data()), static_cast<unsigned int>(in.size()),
                                        out.data(), &out_len) == ROSLZ4_OK;
  return ok && out_len == size;
}

// The records of a chunk's data, which must fill it: the op at each record's start.
std::map<std::uint64_t, std::uint8_t> chunkRecords(const Bytes& data, std::uint64_t chunk_pos) {
  std::map<std::uint64_t, std::uint8_t> ops;
  const std::string what = "a record in the chunk at byte " + std::to_string(chunk_pos);
  for (std::uint64_t p = 0; p < data.size();) {
    const Record r = recordAt(data, p, what);
    if (r.op != kOpMessageData && r.op != kOpConnection) {
      damage(what + ": op " + std::to_string(r.op) + ", not a message or a connection", chunk_pos);
    }
    ops[p] = r.op;
    p = r.end();
  }
  return ops;
}

// A connection the index declares: its topic, and the type and MD5 sum of its messages.
struct Connection {
  std::string topic, datatype, md5sum;
};
using Connections = std::map<std::uint32_t, Connection>;

std::string valueOr(const Fields& f, const char* name) {
  const auto it = f.find(name);
  return it == f.end() ? std::string() : it->second;
}

// The index at pos: a record per connection (a header, then the connection's own header), then
// a chunk info per chunk. Each takes at least 8 bytes: a damaged count runs into the end.
std::vector<ChunkInfo> readIndex(const Bytes& file, std::uint64_t pos, std::uint32_t connections,
                                 std::uint32_t chunks, Connections& declared) {
  for (std::uint32_t i = 0; i < connections; ++i) {
    std::uint64_t next = 0;
    const Fields f = headerAt(file, pos, next, "a connection record");
    if (field<std::uint8_t>(f, "op", "a connection record", pos) != kOpConnection) {
      damage("a connection record of another op", pos);
    }
    const auto id = field<std::uint32_t>(f, "conn", "a connection record", pos);
    const Fields own = headerAt(file, next, pos, "a connection's header");
    declared[id] = {valueOr(f, "topic"), valueOr(own, "type"), valueOr(own, "md5sum")};
  }
  std::vector<ChunkInfo> infos;
  for (std::uint32_t i = 0; i < chunks; ++i) {
    const std::string what = "a chunk info record";
    const Record r = recordAt(file, pos, kOpChunkInfo, what);
    if (field<std::uint32_t>(r.fields, "ver", what, pos) != 1) damage(what + " of another version", pos);
    field<std::uint64_t>(r.fields, "start_time", what, pos);
    field<std::uint64_t>(r.fields, "end_time", what, pos);
    const auto count = field<std::uint32_t>(r.fields, "count", what, pos);
    if (r.data_len != 8ull * count) damage(what + ": its data is not 8 bytes a connection", pos);
    for (std::uint32_t k = 0; k < count; ++k) {
      const std::uint32_t id = u32At(file, r.data_pos + 8ull * k, what);
      if (!declared.count(id)) damage(what + ": connection " + std::to_string(id) + " is not declared", pos);
    }
    infos.push_back({field<std::uint64_t>(r.fields, "chunk_pos", what, pos), count});
    pos = r.end();
  }
  return infos;
}

// A message as the index after its chunk lists it.
struct IndexEntry {
  std::uint64_t time_ns = 0;
  std::uint32_t offset = 0;  // of its record in the chunk's data
  std::uint32_t conn = 0;
};

// The index records after a chunk: each message's time and offset in the chunk's data.
std::vector<IndexEntry> messageIndex(const Bytes& file, std::uint64_t p, std::size_t records,
                                     const Connections& declared) {
  std::vector<IndexEntry> entries;
  for (std::size_t k = 0; k < records; ++k) {
    const std::string what = "an index record";
    const Record r = recordAt(file, p, kOpIndexData, what);
    if (field<std::uint32_t>(r.fields, "ver", what, p) != 1) damage(what + " of another version", p);
    const auto id = field<std::uint32_t>(r.fields, "conn", what, p);
    if (!declared.count(id)) damage(what + ": connection " + std::to_string(id) + " is not declared", p);
    const auto count = field<std::uint32_t>(r.fields, "count", what, p);
    if (r.data_len != 12ull * count) damage(what + ": its data is not 12 bytes a message", p);
    for (std::uint32_t m = 0; m < count; ++m) {
      const std::uint64_t at = r.data_pos + 12ull * m;
      const std::uint64_t ns = u32At(file, at, what) * 1'000'000'000ull + u32At(file, at + 4, what);
      entries.push_back({ns, u32At(file, at + 8, what), id});
    }
    p = r.end();
  }
  return entries;
}

// The message e of a checked chunk's data: its bytes where they are in memory, else read into
// bytes.
BagMessage messageAt(const Bytes& data, const IndexEntry& e, const Connection& c, ChunkBuffer& bytes) {
  const Record r = recordAt(data, e.offset, kOpMessageData, "a message");
  const char* at = data.view(r.data_pos, r.data_len);  // in a decompressed chunk: no copy
  if (!at) {
    bytes.resize(r.data_len);
    data.read(r.data_pos, bytes.size(), bytes.data());
    at = bytes.data();
  }
  return {c.topic, c.datatype, c.md5sum, e.time_ns, reinterpret_cast<const std::uint8_t*>(at), r.data_len};
}

// A chunk as its header and the index records after it give it.
struct Chunk {
  std::uint64_t pos = 0;
  Record record;
  std::string compression;
  std::uint32_t size = 0;  // of its data, decompressed
  std::vector<IndexEntry> entries;
};

// A chunk's header and its index records.
Chunk chunkAt(const Bytes& file, const ChunkInfo& info, const Connections& declared) {
  Chunk c{info.pos, recordAt(file, info.pos, kOpChunk, "a chunk"), {}, 0, {}};
  const auto compression = c.record.fields.find("compression");
  if (compression == c.record.fields.end() ||
      (compression->second != "none" && compression->second != "bz2" && compression->second != "lz4")) {
    damage("a chunk without a known compression (none, bz2, lz4)", info.pos);
  }
  c.compression = compression->second;
  c.entries = messageIndex(file, c.record.end(), info.connections, declared);
  c.size = field<std::uint32_t>(c.record.fields, "size", "a chunk", info.pos);
  if (c.size > kMaxChunkBytes) {
    damage("a chunk of " + std::to_string(c.size) + " bytes (more than 2^30)", info.pos);
  }
  if (c.compression == "none" && c.record.data_len != c.size) {
    damage("an uncompressed chunk of " + std::to_string(c.record.data_len) + " bytes whose size says " +
               std::to_string(c.size),
           info.pos);
  }
  return c;
}

// A message of the index, and the chunk it is in.
struct Placed {
  std::size_t chunk;
  IndexEntry e;
};

// The messages on topics of chunks [first, end), in the order of rosbag's views: by time, then
// by chunk, then by position.
std::vector<Placed> inTimeOrder(const std::vector<Chunk>& chunks, std::size_t first, std::size_t end,
                                const Connections& declared, const std::set<std::string>& topics) {
  std::vector<Placed> order;
  for (std::size_t i = first; i < end; ++i) {
    for (const IndexEntry& e : chunks[i].entries) {
      if (topics.count(declared.at(e.conn).topic)) order.push_back({i, e});
    }
  }
  std::sort(order.begin(), order.end(), [](const Placed& a, const Placed& b) {
    return std::tie(a.e.time_ns, a.chunk, a.e.offset) < std::tie(b.e.time_ns, b.chunk, b.e.offset);
  });
  return order;
}

// The next batch: the distinct chunks at positions from, from + 1, ... < n of a sequence
// (chunk_at(j): the chunk at position j), in the order first met, up to budget bytes of
// decompressed data (one chunk at least); slot maps each to its place in the batch.
// (A chunk kept decompressed costs nothing.)
template <class ChunkAt, class Kept>
std::vector<std::size_t> nextBatch(const std::vector<Chunk>& chunks, std::size_t from,
                                   std::size_t n, ChunkAt chunk_at, Kept kept,
                                   std::uint64_t budget, std::map<std::size_t, std::size_t>& slot) {
  std::vector<std::size_t> ids;
  std::uint64_t total = 0;
  slot.clear();
  for (std::size_t j = from; j < n; ++j) {
    const std::size_t id = chunk_at(j);
    if (slot.count(id)) continue;
    const std::uint64_t size = kept(id) ? 0 : chunks[id].size;
    if (!ids.empty() && total + size > budget) break;
    slot[id] = ids.size();
    ids.push_back(id);
    total += size;
  }
  return ids;
}

// A chunk's data: in place in the file when it is not compressed, else its decompressed bytes.
class ChunkData {
 public:
  ChunkData(std::ifstream& in, const Chunk& c, const ChunkBuffer& unpacked)
      : in_place_(in, c.record.data_pos, c.record.data_len), in_buffer_(unpacked, c.pos),
        packed_(c.compression != "none") {}
  const Bytes& bytes() const { return packed_ ? static_cast<const Bytes&>(in_buffer_) : in_place_; }

 private:
  FileBytes in_place_;
  BufferBytes in_buffer_;
  bool packed_;
};

// A chunk's data: every record in it, and every message offset of the index on a message.
void checkChunkData(const Chunk& c, const Bytes& data) {
  const std::map<std::uint64_t, std::uint8_t> ops = chunkRecords(data, c.pos);
  // rosbag writes each offset at its message record. (Where one lands on a connection record,
  // rosbag reads on from inside that record's second header: a record to refuse too.)
  for (const IndexEntry& e : c.entries) {
    const auto it = ops.find(e.offset);
    if (it == ops.end() || it->second != kOpMessageData) {
      damage("the index points at byte " + std::to_string(e.offset) + " of the chunk, not at a message",
             c.pos);
    }
  }
}

}  // namespace

struct BagWalk::Impl {
  std::ifstream in;
  std::uint64_t file_size = 0;
  Connections declared;
  std::vector<Chunk> chunks;

  // The buffers of a batch, kept from batch to batch: a buffer that is written again is not
  // mapped and cleared by the kernel again.
  std::vector<ChunkBuffer> packed, unpacked;

  // Compressed chunks the walk checked, kept decompressed for the reads after it (up to
  // keep_bytes of them, in the file's order), and the decompressions so far.
  std::map<std::size_t, ChunkBuffer> kept;
  std::uint64_t keep_bytes = 0, kept_bytes = 0;
  std::size_t decompressions = 0;
  bool isKept(std::size_t id) const { return kept.count(id) != 0; }
  // The decompressed data of chunk id, the k-th of the batch unpack was given last.
  const ChunkBuffer& unpackedOf(std::size_t id, std::size_t k) const {
    const auto it = kept.find(id);
    return it != kept.end() ? it->second : unpacked[k];
  }

  // Chunk id, the k-th of the batch just checked, kept decompressed if it is compressed and
  // within keep_bytes.
  void keep(std::size_t id, std::size_t k) {
    if (chunks[id].compression == "none" || kept_bytes + chunks[id].size > keep_bytes) return;
    kept_bytes += chunks[id].size;
    kept[id].swap(unpacked[k]);
  }

  // The data of chunks ids in unpacked (the k-th of ids[k]; empty where not compressed or
  // kept), the compressed ones decompressed on the team; damage at the first (in the order of
  // ids) that does not decompress to its size.
  void unpack(const std::vector<std::size_t>& ids) {
    const FileBytes file(in, 0, file_size);
    if (packed.size() < ids.size()) packed.resize(ids.size()), unpacked.resize(ids.size());
    std::vector<char> due(ids.size(), 0), sound(ids.size(), 1);
    for (std::size_t k = 0; k < ids.size(); ++k) {
      const Record& r = chunks[ids[k]].record;
      unpacked[k].clear();
      if (chunks[ids[k]].compression == "none" || isKept(ids[k])) continue;
      due[k] = 1;
      ++decompressions;
      packed[k].resize(r.data_len);
      file.read(r.data_pos, r.data_len, packed[k].data());
    }
#pragma omp parallel for schedule(dynamic) if (ids.size() > 1)
    for (std::ptrdiff_t k = 0; k < static_cast<std::ptrdiff_t>(ids.size()); ++k) {
      const Chunk& c = chunks[ids[static_cast<std::size_t>(k)]];
      if (due[k]) sound[k] = decompress(packed[k], c.compression, c.size, unpacked[k]);
    }
    for (std::size_t k = 0; k < ids.size(); ++k) {
      const Chunk& c = chunks[ids[k]];
      if (!sound[k]) {
        damage("the chunk (" + c.compression + ") does not decompress to its " + std::to_string(c.size) +
                   " bytes",
               c.pos);
      }
    }
  }
};

std::uint64_t BagWalk::defaultKeepBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  const std::uint64_t most = std::uint64_t{512} << 20;
  return pages > 0 && page > 0 ? std::min(most, std::uint64_t(pages) * page / 8) : most;
}

BagWalk::BagWalk(const std::string& path, std::uint64_t keep_bytes)
    : impl_(std::make_unique<Impl>()) {
  impl_->keep_bytes = keep_bytes;
  std::ifstream& in = impl_->in;
  in.open(path, std::ios::binary);
  if (!in) throw NotABag(std::string("cannot read it: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::uint64_t file_size = static_cast<std::uint64_t>(in.tellg());
  std::uint64_t header_pos = 0;
  const VersionLine version = bagVersion(in, header_pos);
  if (!version.found) throw NotABag("its first line is not a bag's version line (#ROSBAG V2.0)");
  if (!version.is_2_0) {
    throw BagDamage("bag format " + version.text + ": only format 2.0 (ROS since 2010) is read");
  }
  const FileBytes file(in, 0, file_size);

  const Record header = recordAt(file, header_pos, kOpFileHeader, "the file header");
  const auto index_pos = field<std::uint64_t>(header.fields, "index_pos", "the file header", header_pos);
  if (index_pos == 0) {
    throw BagDamage("the bag has no index: its recording did not end (`rosbag reindex` writes one)");
  }
  if (index_pos >= file_size) {
    throw BagDamage("the file ends at byte " + std::to_string(file_size) + ", before its index (at byte " +
                    std::to_string(index_pos) + "): it is cut short");
  }
  if (index_pos < header.end()) {
    damage("the file header's index position " + std::to_string(index_pos) +
               " lies outside the file's records",
           header_pos);
  }
  const std::vector<ChunkInfo> infos = readIndex(
      file, index_pos, field<std::uint32_t>(header.fields, "conn_count", "the file header", header_pos),
      field<std::uint32_t>(header.fields, "chunk_count", "the file header", header_pos), impl_->declared);
  for (const ChunkInfo& info : infos) {
    if (info.pos < header.end() || info.pos >= index_pos) {
      damage("a chunk position " + std::to_string(info.pos) + " outside the chunks", index_pos);
    }
    impl_->chunks.push_back(chunkAt(file, info, impl_->declared));
    for (const IndexEntry& e : impl_->chunks.back().entries) {
      begin_ns_ = std::min(begin_ns_, e.time_ns);
      end_ns_ = std::max(end_ns_, e.time_ns);
    }
  }
  impl_->file_size = file_size;
}

BagWalk::~BagWalk() = default;

bool BagWalk::hasMessages(const std::string& topic) const {
  for (const Chunk& c : impl_->chunks) {
    for (const IndexEntry& e : c.entries) {
      if (impl_->declared.at(e.conn).topic == topic) return true;
    }
  }
  return false;
}

void BagWalk::checkChunks(const std::set<std::string>& topics,
                          const std::function<void(const BagMessage&)>& on_message) {
  const std::vector<Chunk>& chunks = impl_->chunks;
  std::map<std::size_t, std::size_t> slot;
  ChunkBuffer bytes;
  // A batch's chunks are checked in order: the first damage of the file is the one reported.
  for (std::size_t first = 0; first < chunks.size();) {
    const std::vector<std::size_t> ids = nextBatch(
        chunks, first, chunks.size(), [](std::size_t j) { return j; },
        [](std::size_t) { return false; }, kBatchBytes, slot);
    impl_->unpack(ids);
    for (std::size_t k = 0; k < ids.size(); ++k) {
      const ChunkData data(impl_->in, chunks[ids[k]], impl_->unpacked[k]);
      checkChunkData(chunks[ids[k]], data.bytes());
      if (on_message) {
        for (const Placed& m : inTimeOrder(chunks, ids[k], ids[k] + 1, impl_->declared, topics)) {
          on_message(messageAt(data.bytes(), m.e, impl_->declared.at(m.e.conn), bytes));
        }
      }
      impl_->keep(ids[k], k);
    }
    first = ids.back() + 1;
  }
}

void BagWalk::readMessages(const std::set<std::string>& topics,
                           const std::function<bool(const BagMessage&)>& on_message,
                           std::uint64_t batch_bytes) {
  const std::vector<Chunk>& chunks = impl_->chunks;
  const std::vector<Placed> order = inTimeOrder(chunks, 0, chunks.size(), impl_->declared, topics);
  std::map<std::size_t, std::size_t> held;  // a chunk of the batch -> its buffer in unpacked
  ChunkBuffer bytes;
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (!held.count(order[k].chunk)) {  // the next chunks the messages need
      impl_->unpack(nextBatch(
          chunks, k, order.size(), [&](std::size_t j) { return order[j].chunk; },
          [&](std::size_t id) { return impl_->isKept(id); }, batch_bytes, held));
    }
    const std::size_t chunk = order[k].chunk;
    const ChunkData data(impl_->in, chunks[chunk], impl_->unpackedOf(chunk, held.at(chunk)));
    if (!on_message(messageAt(data.bytes(), order[k].e, impl_->declared.at(order[k].e.conn), bytes))) {
      return;
    }
  }
}

std::size_t BagWalk::decompressions() const { return impl_->decompressions; }

}  // namespace upd::ros1::detail
