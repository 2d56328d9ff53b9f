#include "upd/mrpt_bridge/rawlog_writer.h"

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>

#include <filesystem>
#include <stdexcept>

namespace upd::mrpt_bridge {

struct RawlogWriter::Impl {
  mrpt::io::CFileGZOutputStream out;
  std::string part;
  bool open = false;

  void openMember(bool append) {
    std::string err;
    const auto mode = append ? mrpt::io::OpenMode::APPEND : mrpt::io::OpenMode::TRUNCATE;
    if (!out.open(part, 1, err, mode)) throw std::runtime_error("cannot write " + part + ": " + err);
    open = true;
  }
  void close() {
    if (open) out.close();
    open = false;
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
}

RawlogWriter::~RawlogWriter() { impl_->close(); }

void RawlogWriter::write(const mrpt::obs::CObservation& obs) {
  if (!impl_->open) throw std::logic_error("RawlogWriter::write after finish()");
  mrpt::serialization::archiveFrom(impl_->out) << obs;
  if (++written_ % static_cast<std::size_t>(flush_every_) == 0) {
    impl_->close();  // a complete gzip member on disk
    impl_->openMember(true);
  }
}

void RawlogWriter::writeOdometry(double x_m, double y_m, double yaw_rad, double time_s) {
  mrpt::obs::CObservationOdometry odo;
  odo.sensorLabel = "ODOMETRY";
  odo.odometry = mrpt::poses::CPose2D(x_m, y_m, yaw_rad);
  odo.timestamp = mrpt::Clock::fromDouble(time_s);
  write(odo);
}

void RawlogWriter::finish() {
  impl_->close();
  std::filesystem::rename(impl_->part, path_);
}

}  // namespace upd::mrpt_bridge
