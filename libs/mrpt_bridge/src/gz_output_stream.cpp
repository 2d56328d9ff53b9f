#include "upd/mrpt_bridge/gz_output_stream.h"

#include <zlib.h>

#include <algorithm>
#include <stdexcept>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace upd::mrpt_bridge {

namespace {

// data as one gzip member deflated at level into out (its size set to the member's; grown, and
// left uninitialized, where it is short); false where zlib fails.
bool gzipMember(const char* data, std::size_t size, int level, GzOutputStream::Member& out) {
  z_stream s{};
  if (deflateInit2(&s, level, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) return false;
  const std::size_t bound = deflateBound(&s, static_cast<uLong>(size));
  if (out.capacity < bound) out.bytes.reset(new unsigned char[out.capacity = bound]);
  s.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data));
  s.avail_in = static_cast<uInt>(size);
  s.next_out = out.bytes.get();
  s.avail_out = static_cast<uInt>(bound);
  const bool done = deflate(&s, Z_FINISH) == Z_STREAM_END;
  out.size = s.total_out;
  deflateEnd(&s);
  return done;
}

}  // namespace

GzOutputStream::GzOutputStream(const std::string& path, int level, std::size_t member_bytes)
    : path_(path),
      out_(path, std::ios::binary | std::ios::trunc),
      level_(level),
      member_bytes_(std::max<std::size_t>(member_bytes, 1)) {
  if (!out_) throw std::runtime_error("cannot write " + path);
  int threads = 1;
#ifdef _OPENMP
  threads = omp_get_max_threads();
#endif
  batch_members_ = 2 * static_cast<std::size_t>(threads);
}

GzOutputStream::~GzOutputStream() {
  try {
    close();
  } catch (const std::exception&) {  // a destructor does not throw; close() reports it
  }
}

size_t GzOutputStream::Write(const void* buffer, size_t count) {
  const char* p = static_cast<const char*>(buffer);
  pending_.insert(pending_.end(), p, p + count);
  written_ += count;
  if (pending_.size() >= batch_members_ * member_bytes_) flushMembers();
  return count;
}

void GzOutputStream::flushMembers() {
  // (An empty stream is one empty member: a gzip file as gzip and CFileGZOutputStream write it.)
  const std::size_t members =
      std::max<std::size_t>(1, (pending_.size() + member_bytes_ - 1) / member_bytes_);
  if (packed_.size() < members) packed_.resize(members);
  std::vector<char> sound(members, 1);
#pragma omp parallel for schedule(dynamic) if (members > 1)
  for (std::ptrdiff_t m = 0; m < static_cast<std::ptrdiff_t>(members); ++m) {
    const std::size_t from = static_cast<std::size_t>(m) * member_bytes_;
    const std::size_t n = std::min(member_bytes_, pending_.size() - from);
    sound[m] = gzipMember(pending_.data() + from, n, level_, packed_[m]);
  }
  for (std::size_t m = 0; m < members; ++m) {
    if (!sound[m]) throw std::runtime_error("cannot compress the data of " + path_);
    out_.write(reinterpret_cast<const char*>(packed_[m].bytes.get()),
               static_cast<std::streamsize>(packed_[m].size));
  }
  if (!out_) throw std::runtime_error("cannot write " + path_);
  pending_.clear();
}

void GzOutputStream::close() {
  if (!out_.is_open()) return;
  if (!pending_.empty() || written_ == 0) flushMembers();
  out_.close();
  if (!out_) throw std::runtime_error("cannot write " + path_);
}

size_t GzOutputStream::Read(void*, size_t) {
  throw std::logic_error("GzOutputStream " + path_ + ": an output stream cannot be read");
}

uint64_t GzOutputStream::Seek(int64_t, mrpt::io::CStream::TSeekOrigin) {
  throw std::logic_error("GzOutputStream " + path_ + ": an output stream cannot seek");
}

}  // namespace upd::mrpt_bridge
