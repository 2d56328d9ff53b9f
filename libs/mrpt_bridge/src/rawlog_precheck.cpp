#include "rawlog_precheck.h"

#include "rawlog_precheck_cursor.h"

#include <mrpt/obs/CObservation.h>
#include <mrpt/rtti/CObject.h>

#include <algorithm>
#include <cstring>
#include <iterator>
#include <string>
#include <stdexcept>
#include <type_traits>

namespace upd::mrpt_bridge::detail {

size_t LookaheadStream::Read(void* buffer, size_t count) {
  auto* out = static_cast<std::uint8_t*>(buffer);
  std::size_t done = std::min(count, ahead_.size() - head_);
  if (done > 0) {
    std::memcpy(out, ahead_.data() + head_, done);
    head_ += done;
    if (head_ == ahead_.size()) {
      ahead_.clear();
      head_ = 0;
    }
  }
  if (done < count) done += in_.Read(out + done, count - done);
  return done;
}

size_t LookaheadStream::Write(const void*, size_t) {
  throw std::logic_error("LookaheadStream is read-only");
}

uint64_t LookaheadStream::Seek(int64_t, TSeekOrigin) {
  throw std::logic_error("LookaheadStream reads forward only");
}

uint64_t LookaheadStream::getTotalBytesCount() const { return in_.getTotalBytesCount(); }

uint64_t LookaheadStream::getPosition() const {
  return in_.getPosition() - (ahead_.size() - head_);
}

bool LookaheadStream::peek(std::size_t offset, void* out, std::size_t count) {
  const std::size_t need = offset + count;
  while (ahead_.size() - head_ < need) {
    if (head_ > 0) {  // keep only what is not consumed
      ahead_.erase(ahead_.begin(), ahead_.begin() + static_cast<std::ptrdiff_t>(head_));
      head_ = 0;
    }
    const std::size_t have = ahead_.size();
    // In steps of at most 1 MiB: a corrupt size near the end of a file asks for more than is there,
    // and is not allocated ahead of the bytes.
    const std::size_t chunk = std::clamp<std::size_t>(need - have, 4096, 1 << 20);
    ahead_.resize(have + chunk);
    const std::size_t got = in_.Read(ahead_.data() + have, chunk);
    ahead_.resize(have + got);
    if (got == 0) {
      end_ = in_.getPosition();
      return false;
    }
  }
  std::memcpy(out, ahead_.data() + head_ + offset, count);
  return true;
}

bool readHeader(Cursor& c, ObjectHeader& h) {
  std::uint8_t length = 0;
  if (!c.value(length)) return false;
  h.has_end_flag = (length & 0x80) != 0;
  if (!h.has_end_flag) {
    std::uint8_t zeros[3];
    if (!c.bytes(zeros, 3) || zeros[0] || zeros[1] || zeros[2]) return false;
  }
  length &= 0x7F;
  if (length > 120) return false;
  std::string name(length, '\0');
  if (length > 0 && !c.bytes(name.data(), length)) return false;
  // MRPT takes the name as a C string: up to its first NUL, whatever the length said.
  name.resize(std::min(name.size(), name.find('\0')));
  const auto ns = name.rfind("::");
  h.class_name = ns == std::string::npos ? name : name.substr(ns + 2);
  h.full_name = name;
  if (!h.has_end_flag) {
    std::int32_t v = 0;
    if (!c.value(v) || v < 0 || v >= 255) return false;
    h.version = v;
    return true;
  }
  if (name == "nullptr") return true;
  std::uint8_t v = 0;
  if (!c.value(v)) return false;
  h.version = v;
  return true;
}

bool withinBound(const char* field, std::uint64_t value, std::uint64_t at, std::uint64_t max,
                 const char* unit, std::string& why) {
  if (value <= max) return true;
  why = std::string(field) + " " + std::to_string(value) + " at byte " + std::to_string(at) +
        " (more than " + std::to_string(max) + " " + unit + ")";
  return false;
}

namespace {

// A CPose2D object (version 0: floats, 1: doubles) through its end flag.
bool walkPose2D(Cursor& c) {
  ObjectHeader pose;
  if (!readHeader(c, pose) || pose.class_name != "CPose2D" || pose.version > 1) return false;
  c.skip(3 * (pose.version == 0 ? sizeof(float) : sizeof(double)));
  return !pose.has_end_flag || c.endFlag();
}

// The upper triangle of a 3 x 3 symmetric matrix as MRPT writes it (in float, or double).
void skipTriangle(Cursor& c, bool in_float) { c.skip(6 * (in_float ? sizeof(float) : sizeof(double))); }

// A scan-matching action's pose distribution, its header read, through its end flag (Read): the
// sizes MRPT allocates by before it reads the elements (CPosePDFParticles' particles,
// CPosePDFSOG's modes, CPosePDFGrid's cells), and a grid's cells against its sides, which MRPT
// indexes them by when it takes the mean. A layout not walked here (an old version) is
// OtherLayout.
Parse checkPosePdf(Cursor& c, const ObjectHeader& pdf, std::string& why) {
  const auto end = [&] { return !pdf.has_end_flag || c.endFlag() ? Parse::Read : Parse::OtherLayout; };
  const std::uint64_t at = c.position();
  if (pdf.class_name == "CPosePDFGaussian" && (pdf.version == 1 || pdf.version == 2)) {
    // The mean, then the covariance's upper triangle (version 1 in float).
    if (!walkPose2D(c)) return Parse::OtherLayout;
    skipTriangle(c, pdf.version == 1);
    return end();
  }
  if (pdf.class_name == "CPosePDFGaussianInf" && pdf.version == 0) {
    c.skip(3 * sizeof(double));  // the mean
    skipTriangle(c, false);      // the information matrix
    return end();
  }
  if ((pdf.class_name == "CPosePDFParticles" && pdf.version <= 1) ||
      (pdf.class_name == "CPosePDFSOG" && pdf.version <= 2)) {
    const bool particles = pdf.class_name == "CPosePDFParticles";
    std::uint32_t n = 0;
    if (!c.value(n)) return Parse::OtherLayout;
    if (!withinBound(particles ? "particle count" : "mode count", n, at, kMaxPosePdfElements,
                     particles ? "particles" : "modes", why)) {
      why = "corrupt " + pdf.class_name + ": " + why;
      return Parse::Impossible;
    }
    if (particles) {
      if (pdf.version == 0) return Parse::OtherLayout;  // (CPose2D objects)
      c.skip(std::uint64_t{n} * 4 * sizeof(double));  // log weight, x, y, phi
      return end();
    }
    for (std::uint32_t i = 0; i < n; ++i) {  // log weight, mean, covariance's triangle
      c.skip(sizeof(double));
      if (!walkPose2D(c)) return Parse::OtherLayout;
      skipTriangle(c, pdf.version == 1);
    }
    return end();
  }
  if (pdf.class_name != "CPosePDFGrid" || pdf.version != 0) return Parse::OtherLayout;
  c.skip(8 * sizeof(double));  // the bounds and resolutions
  const std::uint64_t sides_at = c.position();
  std::int32_t side[4] = {};  // x, y, phi, and x * y
  for (std::int32_t& v : side) {
    if (!c.value(v)) return Parse::OtherLayout;
  }
  c.skip(3 * sizeof(std::int32_t));  // the left indices
  const std::uint64_t count_at = c.position();
  std::uint32_t count = 0;
  if (!c.value(count)) return Parse::OtherLayout;
  if (side[0] < 0 || side[1] < 0 || side[2] < 0 ||
      static_cast<std::int64_t>(side[0]) * side[1] != side[3]) {
    why = "corrupt CPosePDFGrid: sides " + std::to_string(side[0]) + " x " +
          std::to_string(side[1]) + " x " + std::to_string(side[2]) + " with " +
          std::to_string(side[3]) + " cells a layer, at byte " + std::to_string(sides_at);
    return Parse::Impossible;
  }
  if (!withinBound("cell count", count, count_at, kMaxPoseGridCells, "cells", why)) {
    why = "corrupt CPosePDFGrid: " + why;
    return Parse::Impossible;
  }
  if (count != static_cast<std::uint64_t>(side[3]) * static_cast<std::uint64_t>(side[2])) {
    why = "corrupt CPosePDFGrid: " + std::to_string(count) + " cells at byte " +
          std::to_string(count_at) + " for sides " + std::to_string(side[0]) + " x " +
          std::to_string(side[1]) + " x " + std::to_string(side[2]);
    return Parse::Impossible;
  }
  c.skip(std::uint64_t{count} * sizeof(double));
  return end();
}

// What follows either estimate in a CActionRobotMovement2D (versions 4-7): velocities,
// encoders, the timestamp.
Parse checkMovementTail(Cursor& c, int version) {
  std::uint8_t has_velocities = 0, has_encoders = 0;
  if (!c.value(has_velocities)) return Parse::OtherLayout;
  if (version >= 7) {
    if (has_velocities) c.skip(3 * sizeof(double));  // TTwist2D
  } else {
    c.skip(2 * sizeof(double));
  }
  if (!c.value(has_encoders)) return Parse::OtherLayout;
  if (version < 7 || has_encoders) c.skip(2 * sizeof(std::int32_t));
  if (version >= 6) c.skip(sizeof(std::uint64_t));  // the timestamp
  return Parse::Read;
}

// CActionRobotMovement2D::serializeFrom of MRPT 2.5.8, versions 4-7, up to its end flag: an
// odometry estimate carries its raw increment (a CPose2D object) and the motion model MRPT rebuilds
// the distribution from while reading.
Parse checkMovement2D(Cursor& c, int version, std::string& why) {
  if (version < 4 || version > 7) return Parse::OtherLayout;
  std::int32_t method = 0;
  if (!c.value(method)) return Parse::OtherLayout;
  if (method != 0) {
    // Not an odometry estimate (emOdometry = 0): scan matching (1), whose pose distribution
    // object follows (MRPT uses what it reads there as a CPosePDF without a check: another
    // object, or none, ends the process).
    if (method != 1) {
      why = "unknown estimation method " + std::to_string(method) +
            " (0 odometry, 1 scan matching)";
      return Parse::Impossible;
    }
    ObjectHeader pdf;
    if (!readHeader(c, pdf)) return Parse::OtherLayout;
    static const char* const kPosePdfs[] = {"CPosePDFGaussian", "CPosePDFGaussianInf",
                                            "CPosePDFParticles", "CPosePDFGrid", "CPosePDFSOG"};
    if (std::find(std::begin(kPosePdfs), std::end(kPosePdfs), pdf.class_name) ==
        std::end(kPosePdfs)) {
      why = "a " + (pdf.class_name.empty() ? std::string("nameless object") : pdf.class_name) +
            " where scan matching's pose distribution (a CPosePDF) belongs";
      return Parse::Impossible;
    }
    const Parse p = checkPosePdf(c, pdf, why);
    return p == Parse::Read ? checkMovementTail(c, version) : p;
  }
  if (!walkPose2D(c)) return Parse::OtherLayout;  // the raw odometry increment
  std::int32_t model = 0;
  std::uint32_t particles = 0;
  if (!c.value(model)) return Parse::OtherLayout;
  c.skip(6 * sizeof(float));  // the Gaussian model's a1..a4, minStdXY, minStdPHI
  if (!c.value(particles)) return Parse::OtherLayout;
  // MRPT draws particles for any model but mmGaussian (0); mmThrun is 1.
  if (model != 0 && model != 1) {
    why = "unknown motion model " + std::to_string(model) +
          " (0 Gaussian, 1 Thrun; MRPT would draw its " + std::to_string(particles) + " particles)";
    return Parse::Impossible;
  }
  if (model == 1 && particles > kMaxOdometryParticles) {
    why = "a motion model of " + std::to_string(particles) + " particles (more than " +
          std::to_string(kMaxOdometryParticles) +
          "; MRPT draws every one while reading the object)";
    return Parse::Impossible;
  }
  c.skip((version >= 5 ? 6 : 4) * sizeof(float));  // the Thrun model's alphas and extra noise
  return checkMovementTail(c, version);
}

// CActionRobotMovement3D::serializeFrom of MRPT 2.5.8, versions 0-1, up to its end flag: the
// estimation method, the pose change (a CPose3DPDFGaussian object, version 1: the mean, a CPose3D
// object, then the covariance's upper triangle of 21 doubles), a flag for each velocity and the
// velocities (a count each, which MRPT resizes to), the timestamp (version 1).
Parse checkMovement3D(Cursor& c, int version, std::string& why) {
  if (version > 1) return Parse::OtherLayout;
  c.skip(sizeof(std::uint32_t));  // the estimation method (MRPT keeps it, reads nothing by it)
  ObjectHeader pdf;
  if (!readHeader(c, pdf) || pdf.class_name != "CPose3DPDFGaussian" || pdf.version != 1) {
    return Parse::OtherLayout;
  }
  const Parse p = checkPose(c, why);
  if (p != Parse::Read) return p;
  c.skip(21 * sizeof(double));
  if (pdf.has_end_flag && !c.endFlag()) return Parse::OtherLayout;
  const struct {
    const char* field;
    std::size_t bytes;  // an element's
  } vectors[] = {{"velocity flag count", 1}, {"velocity count", sizeof(float)}};
  for (const auto& v : vectors) {
    const std::uint64_t at = c.position();
    std::uint32_t n = 0;
    if (!c.value(n)) return Parse::OtherLayout;
    if (!withinBound(v.field, n, at, kMaxVelocityComponents, "components", why)) {
      return Parse::Impossible;
    }
    c.skip(std::uint64_t{n} * v.bytes);
  }
  if (version >= 1) c.skip(sizeof(std::uint64_t));  // the timestamp
  return Parse::Read;
}

// A robot movement (2D or 3D) of the version given, its header read, up to its end flag.
Parse checkMovement(Cursor& c, const ObjectHeader& h, std::string& why) {
  return h.class_name == "CActionRobotMovement2D" ? checkMovement2D(c, h.version, why)
                                                  : checkMovement3D(c, h.version, why);
}

// Why a frame's observation count or a collection's action count read at byte `at` is past its
// bound ("corrupt CSensoryFrame: observation count ..."), or "".
std::string containerCountPastBound(bool frame, std::uint32_t count, std::uint64_t at) {
  std::string why;
  if (frame) {
    if (!withinBound("observation count", count, at, kMaxObservationsPerFrame, "observations",
                     why)) {
      return "corrupt CSensoryFrame: " + why;
    }
  } else if (!withinBound("action count", count, at, kMaxActionsPerCollection, "actions", why)) {
    return "corrupt CActionCollection: " + why;
  }
  return {};
}

// Action i of n in a CActionCollection, through its end flag: MRPT keeps each action as a
// deep-copying pointer made from what it read cast to a CAction: anything else, or a null
// object, is copied through a null pointer.
Parse checkAction(Cursor& c, std::uint32_t i, std::uint32_t n, std::string& why) {
  ObjectHeader action;
  if (!readHeader(c, action)) return Parse::OtherLayout;
  const std::string where = std::to_string(i + 1) + " of " + std::to_string(n);
  if (action.class_name != "CActionRobotMovement2D" &&
      action.class_name != "CActionRobotMovement3D") {
    why = "corrupt CActionCollection: action " + where + " is " +
          (action.class_name == "nullptr" ? std::string("a null object")
                                          : "a " + action.class_name + ", not an action");
    return Parse::Impossible;
  }
  const Parse p = checkMovement(c, action, why);
  if (p == Parse::Impossible) {
    why = "corrupt " + action.class_name + " (action " + where + " in a CActionCollection): " + why;
    return p;
  }
  if (p == Parse::OtherLayout || (action.has_end_flag && !c.endFlag())) return Parse::OtherLayout;
  return Parse::Read;
}

// CActionCollection::serializeFrom, version 0: a count, then the action objects.
Parse checkActions(Cursor& c, int version, std::string& why) {
  if (version != 0) return Parse::OtherLayout;
  const std::uint64_t at = c.position();
  std::uint32_t actions = 0;
  if (!c.value(actions)) return Parse::OtherLayout;
  if (!(why = containerCountPastBound(false, actions, at)).empty()) return Parse::Impossible;
  for (std::uint32_t i = 0; i < actions; ++i) {
    const Parse p = checkAction(c, i, actions, why);
    if (p != Parse::Read) return p;
  }
  return c.endFlag() ? Parse::Read : Parse::OtherLayout;
}

// Observation i of n in a CSensoryFrame of the version given, through its end flag.
Parse checkFrameObservation(Cursor& c, int version, std::uint32_t i, std::uint32_t n,
                            std::string& why) {
  ObjectHeader obs;
  if (!readHeader(c, obs)) return Parse::OtherLayout;
  const std::string where = std::to_string(i + 1) + " of " + std::to_string(n);
  if (version == 0 && obs.class_name == "nullptr") {
    why = "corrupt CSensoryFrame: observation " + where +
          " is a null object (MRPT sets a version-0 frame's timestamp through each)";
    return Parse::Impossible;
  }
  // MRPT reads any class it knows before the frame can see it is not an observation (a
  // CActionCollection in a frame resizes its list to the count it reads).
  const auto* known = mrpt::rtti::findRegisteredClass(obs.full_name);
  if (known && !known->derivedFrom(CLASS_ID(mrpt::obs::CObservation))) {
    why = "corrupt CSensoryFrame: observation " + where + " is a " + obs.class_name +
          ", not an observation";
    return Parse::Impossible;
  }
  const Parse p = checkObservation(c, obs, why);
  if (p == Parse::Impossible) {
    why = "corrupt " + obs.class_name + " (observation " + where + " in a CSensoryFrame): " + why;
  }
  return p;
}

// CSensoryFrame::serializeFrom, versions 0-2: before version 2 the frame's ID, in version 0
// its timestamp (which MRPT then sets on every observation, through its pointer); a count;
// the observation objects.
Parse checkFrame(Cursor& c, int version, std::string& why) {
  if (version < 0 || version > 2) return Parse::OtherLayout;
  if (version < 2) c.skip(sizeof(std::uint32_t));  // the ID
  if (version == 0) c.skip(sizeof(std::int64_t));  // the timestamp
  const std::uint64_t at = c.position();
  std::uint32_t count = 0;
  if (!c.value(count)) return Parse::OtherLayout;
  if (!(why = containerCountPastBound(true, count, at)).empty()) return Parse::Impossible;
  for (std::uint32_t i = 0; i < count; ++i) {
    const Parse p = checkFrameObservation(c, version, i, count, why);
    if (p != Parse::Read) return p;
  }
  return c.endFlag() ? Parse::Read : Parse::OtherLayout;
}

Parse checkTopLevel(Cursor& c, const ObjectHeader& top, std::string& why) {
  if (top.class_name == "CActionCollection") return checkActions(c, top.version, why);
  if (top.class_name == "CSensoryFrame") return checkFrame(c, top.version, why);
  Parse p = Parse::OtherLayout;
  if (top.class_name == "CActionRobotMovement2D" || top.class_name == "CActionRobotMovement3D") {
    p = checkMovement(c, top, why);
    if (p == Parse::Read && top.has_end_flag && !c.endFlag()) p = Parse::OtherLayout;
  } else if (top.class_name.rfind("CPosePDF", 0) == 0) {
    return checkPosePdf(c, top, why);  // (its reasons name the class)
  } else {
    p = checkObservation(c, top, why);
    // A part of an observation on its own (a rawlog holds none; a damaged one may): MRPT would
    // read it before the reader skips it, allocating by its sizes.
    if (p == Parse::OtherLayout && !c.ranOut()) {
      c.restart();
      p = checkPart(c, top.class_name, why);
    }
  }
  if (p == Parse::Impossible) why = "corrupt " + top.class_name + ": " + why;
  return p;
}

// truncatedAt() for an object whose walk ran past the end of the stream (a count cut by the end of
// a file would be read with bytes that were never there, and a list resized to it), or "" when it
// did not, or the stream ended before the object's first byte.
std::string truncation(const Cursor& c, const LookaheadStream& in) {
  const auto end = in.knownEnd();
  if (!c.ranOut() || !end || *end <= c.start()) return {};
  return truncatedAt(*end);
}

}  // namespace

std::string truncatedAt(std::uint64_t end) {
  return "truncated, the file ends inside it, at byte " + std::to_string(end);
}

bool peekContainerHead(LookaheadStream& in, ContainerHead& head) {
  Cursor c(in);
  ObjectHeader h;
  if (!readHeader(c, h)) return false;
  head = ContainerHead{};
  head.frame = h.class_name == "CSensoryFrame";
  head.version = h.version;
  head.has_end_flag = h.has_end_flag;
  if (head.frame && h.version >= 0 && h.version <= 2) {
    if (h.version < 2) c.skip(sizeof(std::uint32_t));  // the ID
    if (h.version == 0 && !c.value(head.timestamp)) return false;
  } else if (h.class_name != "CActionCollection" || h.version != 0) {
    return false;
  }
  if (!c.value(head.count)) return false;
  head.bytes = c.walked();
  return true;
}

std::string precheckContainerHead(LookaheadStream& in, const ContainerHead& head) {
  return containerCountPastBound(head.frame, head.count,
                                 in.getPosition() + head.bytes - sizeof(std::uint32_t));
}

std::string precheckNextElement(LookaheadStream& in, const ContainerHead& head,
                                std::uint32_t index) {
  Cursor c(in);
  std::string why;
  const Parse p = head.frame ? checkFrameObservation(c, head.version, index, head.count, why)
                             : checkAction(c, index, head.count, why);
  return p == Parse::Impossible ? why : truncation(c, in);
}

std::string precheckNextObject(LookaheadStream& in, std::size_t* checked_bytes) {
  if (checked_bytes) *checked_bytes = 0;
  Cursor c(in);
  ObjectHeader top;
  if (!readHeader(c, top)) return truncation(c, in);
  std::string why;
  const Parse p = checkTopLevel(c, top, why);
  if (p == Parse::Impossible) return why;
  if (std::string cut = truncation(c, in); !cut.empty()) return cut;
  if (p == Parse::Read && checked_bytes) *checked_bytes = c.walked();
  return {};
}

}  // namespace upd::mrpt_bridge::detail
