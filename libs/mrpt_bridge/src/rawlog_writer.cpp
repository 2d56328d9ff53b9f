#include "upd/mrpt_bridge/rawlog_writer.h"

#include <mrpt/io/CStream.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>
#include <zlib.h>

#include <cerrno>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <deque>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

namespace upd::mrpt_bridge {

namespace {

// An output stream into a byte vector, which keeps its capacity from object to object.
class ByteSink : public mrpt::io::CStream {
 public:
  explicit ByteSink(std::vector<std::uint8_t>& bytes) : bytes_(bytes) {}
  size_t Write(const void* buffer, size_t count) override {
    const auto* p = static_cast<const std::uint8_t*>(buffer);
    bytes_.insert(bytes_.end(), p, p + count);
    return count;
  }
  size_t Read(void*, size_t) override { throw std::logic_error("ByteSink cannot be read"); }
  uint64_t Seek(int64_t, mrpt::io::CStream::TSeekOrigin) override {
    throw std::logic_error("ByteSink cannot seek");
  }
  uint64_t getTotalBytesCount() const override { return bytes_.size(); }
  uint64_t getPosition() const override { return bytes_.size(); }

 private:
  std::vector<std::uint8_t>& bytes_;
};

// One serialized observation, and whether its gzip member ends after it.
struct Item {
  std::vector<std::uint8_t> bytes;
  bool end_member = false;
};

}  // namespace

// The caller serializes; the writer thread compresses and writes, in order. The queue holds at
// most kMaxQueuedBytes: beyond that write() waits for the writer (no observation is dropped).
struct RawlogWriter::Impl {
  static constexpr std::size_t kMaxQueuedBytes = std::size_t(128) << 20;
  static constexpr std::size_t kSpareBuffers = 4;

  std::string part;
  gzFile out = nullptr;  // (the writer thread's once it runs)

  std::mutex m;
  std::condition_variable changed;  // an item queued or written, or the end asked
  std::deque<Item> queue;
  std::vector<std::vector<std::uint8_t>> spare;  // written items' buffers, for the next ones
  std::size_t queued_bytes = 0;
  bool writing = false, stop = false;
  bool ended = false;  // (the owner's: end() called)
  std::size_t done = 0;   // the observations compressed into the file
  std::size_t saved = 0;  // of those, the ones in members closed without error
  std::string error;   // the writer's first failure (what follows it is not written)
  std::thread writer;

  // zlib's calls as CFileGZOutputStream makes them (gzopen "wb1" / "ab1", gzwrite, gzclose):
  // the same bytes. Unlike it, a gzclose that fails (the last of a member's data not written)
  // is an error, not silence.
  void openMember(bool append) {
    errno = 0;
    out = gzopen(part.c_str(), append ? "ab1" : "wb1");
    if (out == nullptr) fail();
  }
  void write(const std::vector<std::uint8_t>& bytes) {
    errno = 0;
    const int n = static_cast<int>(bytes.size());
    if (n > 0 && gzwrite(out, bytes.data(), static_cast<unsigned>(n)) != n) fail();
  }
  // Closes the member; throws where its data did not reach the file.
  void closeMember() {
    if (out == nullptr) return;
    errno = 0;
    const int status = gzclose(out);
    out = nullptr;
    if (status != Z_OK) fail();
  }
  [[noreturn]] void fail() const {
    throw std::runtime_error("cannot write " + part + ": " +
                             (errno != 0 ? std::strerror(errno) : "zlib failed"));
  }

  // The writer thread: each item compressed into the file, a member closed (complete on disk)
  // where one ends.
  void run() {
    std::unique_lock<std::mutex> lock(m);
    for (;;) {
      changed.wait(lock, [&] { return stop || !queue.empty(); });
      if (queue.empty()) return;
      Item item = std::move(queue.front());
      queue.pop_front();
      writing = true;
      const bool failed = !error.empty();
      lock.unlock();
      std::string failure;
      bool wrote = false, closed = false;
      if (!failed) {
        try {
          write(item.bytes);
          wrote = true;
          if (item.end_member) {
            closeMember();  // (a complete member on disk)
            closed = true;
            openMember(true);
          }
        } catch (const std::exception& e) {
          failure = e.what();
        }
      }
      lock.lock();
      if (error.empty()) error = failure;
      if (wrote) ++done;
      if (closed) saved = done;  // (a member that could not be reopened after it still counts)
      queued_bytes -= item.bytes.size();
      if (spare.size() < kSpareBuffers) spare.push_back(std::move(item.bytes));
      writing = false;
      changed.notify_all();
    }
  }

  void throwIfFailed() {
    std::lock_guard<std::mutex> lock(m);
    if (!error.empty()) throw std::runtime_error(error);
  }

  std::vector<std::uint8_t> buffer() {
    std::lock_guard<std::mutex> lock(m);
    if (spare.empty()) return {};
    std::vector<std::uint8_t> b = std::move(spare.back());
    spare.pop_back();
    b.clear();
    return b;
  }

  void push(Item item) {
    std::unique_lock<std::mutex> lock(m);
    // (An item larger than the queue waits for the queue to empty.)
    changed.wait(lock, [&] {
      return queued_bytes == 0 || queued_bytes + item.bytes.size() <= kMaxQueuedBytes ||
             !error.empty();
    });
    queued_bytes += item.bytes.size();
    queue.push_back(std::move(item));
    changed.notify_all();
  }

  void drain() {
    std::unique_lock<std::mutex> lock(m);
    changed.wait(lock, [&] { return queue.empty() && !writing; });
  }

  // Everything queued written, the writer thread ended, the file closed (a failure to close
  // kept as the writer's error).
  void end() {
    ended = true;
    {
      std::lock_guard<std::mutex> lock(m);
      stop = true;
    }
    changed.notify_all();
    if (writer.joinable()) writer.join();
    try {
      closeMember();
      if (error.empty()) saved = done;
    } catch (const std::exception& e) {
      if (error.empty()) error = e.what();
    }
  }
};

RawlogWriter::RawlogWriter(const std::string& path, int flush_every)
    : impl_(std::make_unique<Impl>()), path_(path), flush_every_(flush_every) {
  if (flush_every < 1) {
    throw std::invalid_argument("rawlog flush_every = " + std::to_string(flush_every) +
                                ": must be >= 1");
  }
  impl_->part = partPath();
  impl_->openMember(false);
  impl_->writer = std::thread([impl = impl_.get()] { impl->run(); });
}

RawlogWriter::~RawlogWriter() { impl_->end(); }

void RawlogWriter::write(const mrpt::obs::CObservation& obs) {
  if (impl_->ended) throw std::logic_error("RawlogWriter::write after finish()");
  impl_->throwIfFailed();
  Item item{impl_->buffer(), false};
  ByteSink sink(item.bytes);
  mrpt::serialization::archiveFrom(sink) << obs;
  item.end_member = ++written_ % static_cast<std::size_t>(flush_every_) == 0;
  impl_->push(std::move(item));
}

void RawlogWriter::writeOdometry(double x_m, double y_m, double yaw_rad, double time_s) {
  mrpt::obs::CObservationOdometry odo;
  odo.sensorLabel = "ODOMETRY";
  odo.odometry = mrpt::poses::CPose2D(x_m, y_m, yaw_rad);
  odo.timestamp = mrpt::Clock::fromDouble(time_s);
  write(odo);
}

std::size_t RawlogWriter::saved() const {
  std::lock_guard<std::mutex> lock(impl_->m);
  return impl_->saved;
}

void RawlogWriter::drain() {
  impl_->drain();
  impl_->throwIfFailed();
}

void RawlogWriter::finish() {
  impl_->end();
  impl_->throwIfFailed();
  std::filesystem::rename(impl_->part, path_);
}

}  // namespace upd::mrpt_bridge
