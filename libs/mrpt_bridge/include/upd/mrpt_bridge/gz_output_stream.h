// An MRPT output stream to a gzip file whose members are compressed on every core: what
// mrpt::io::CFileGZOutputStream writes at its level (a rawlog that rawlog-edit, RawLogViewer,
// gzip and `upd playback` read), the writing thread free while a batch of members is deflated.
// A gzip file of several members reads as one stream (RFC 1952; zlib's gzread, which MRPT's
// CFileGZInputStream uses, reads them one after the other).
#pragma once

#include <mrpt/io/CStream.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace upd::mrpt_bridge {

class GzOutputStream : public mrpt::io::CStream {
 public:
  /// Opens path (truncated). Throws std::runtime_error naming it when it cannot be written.
  /// Each member holds member_bytes of the data (the last one less), deflated at level (1:
  /// fastest, as CFileGZOutputStream's default).
  explicit GzOutputStream(const std::string& path, int level = 1,
                          std::size_t member_bytes = 1u << 20);
  /// Closes the file as close() does, as MRPT's streams do, but without a word when that fails:
  /// call close() to hear of it.
  ~GzOutputStream() override;

  size_t Write(const void* buffer, size_t count) override;
  /// Compresses and writes what is buffered, and closes the file. Throws std::runtime_error
  /// naming the file when it cannot be written.
  void close();

  size_t Read(void*, size_t) override;                              ///< throws: an output stream
  uint64_t Seek(int64_t, mrpt::io::CStream::TSeekOrigin) override;  ///< throws
  uint64_t getTotalBytesCount() const override { return written_; }
  uint64_t getPosition() const override { return written_; }

  /// A deflated member's bytes, kept from batch to batch (not cleared again by the kernel).
  struct Member {
    std::unique_ptr<unsigned char[]> bytes;
    std::size_t capacity = 0, size = 0;
  };

 private:
  /// Deflates the members buffered (on every core) and writes them in order.
  void flushMembers();

  std::string path_;
  std::ofstream out_;
  int level_;
  std::size_t member_bytes_;
  std::size_t batch_members_;
  std::vector<char> pending_;  ///< data not yet deflated
  std::vector<Member> packed_;
  std::uint64_t written_ = 0;  ///< bytes of data taken
};

}  // namespace upd::mrpt_bridge
