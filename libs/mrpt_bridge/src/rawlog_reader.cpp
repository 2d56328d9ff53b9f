#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/maps/registerAllClasses.h>
#include <mrpt/obs/registerAllClasses.h>

#include "mrpt_util.h"
#include "rawlog_precheck.h"
#include "upd/mrpt_bridge/pose_source.h"

#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <vector>

namespace upd::mrpt_bridge {

const char* toString(RawlogLayout layout) {
  switch (layout) {
    case RawlogLayout::Empty:
      return "empty";
    case RawlogLayout::ActionsAndFrames:
      return "actions + sensory frames";
    case RawlogLayout::ObservationsOnly:
      return "observations only";
    case RawlogLayout::Mixed:
      return "mixed (actions + sensory frames and bare observations)";
  }
  return "unknown";
}

std::string RawlogEntry::className() const {
  return observation ? detail::shortClassName(*observation) : std::string();
}

std::size_t RawlogStats::skippedTotal() const {
  std::size_t n = 0;
  for (const auto& [reason, count] : skipped) n += count;
  return n;
}

std::string RawlogStats::summary() const {
  std::ostringstream os;
  os << objects << " objects (" << action_collections << " action collections, " << sensory_frames
     << " sensory frames): " << entries << " observations";
  if (!entries_by_class.empty()) {
    os << " (";
    bool first = true;
    for (const auto& [name, count] : entries_by_class) {
      os << (first ? "" : ", ") << count << " " << name;
      first = false;
    }
    os << ")";
  }
  os << ", " << odometry_actions << " odometry actions";
  if (!skipped.empty()) {
    os << "; skipped:";
    for (const auto& [reason, count] : skipped) os << " " << count << " x " << reason << ";";
  }
  return os.str();
}

std::string detectImagesDirectory(const std::string& rawlog_path) {
  // CRawlog::detectImagesDirectory() of MRPT 2.5.8 joins the directory and the names without a
  // separator ("/data/runImages"), so it never finds "/data/run_Images": the same search, with
  // std::filesystem.
  namespace fs = std::filesystem;
  const fs::path file(rawlog_path);
  const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
  const std::string stem = file.stem().string();
  std::error_code ec;
  for (const char* suffix : {"_Images", "_images", "_IMAGES"}) {
    const fs::path candidate = dir / (stem + suffix);
    if (fs::is_directory(candidate, ec)) return candidate.string();
  }
  return (dir / "Images").string();
}

namespace {

// MRPT nests "Exception while parsing typed object 'X' from <stream> for file '<path>'" once per
// level: keep the chain of classes and the innermost message.
std::string describeReadError(const std::string& what) {
  std::string msg = detail::condenseMessage(what);
  const std::string head = "Exception while parsing typed object '";
  std::string chain;
  for (;;) {
    if (msg.rfind(head, 0) != 0) break;
    const auto name_end = msg.find('\'', head.size());
    if (name_end == std::string::npos) break;
    std::string name = msg.substr(head.size(), name_end - head.size());
    if (name.find(' ') != std::string::npos) break;  // not a class name: keep the text as is
    const auto ns = name.rfind("::");
    if (ns != std::string::npos) name = name.substr(ns + 2);
    chain += (chain.empty() ? "" : " > ") + name;
    // Skip " from ... for file '...'" up to the ": " that starts the next level.
    const auto next = msg.find("': ", name_end + 1);
    if (next == std::string::npos) {
      msg.clear();
      break;
    }
    msg = msg.substr(next + 3);
  }
  if (chain.empty()) return msg;
  return "in " + chain + (msg.empty() ? std::string() : ": " + msg);
}

// The longest move a robot makes between two observations [m]: beyond it a pose change is
// corrupt (a flipped bit in a double), and would carry every later frame kilometres off the map.
constexpr double kMaxMovementM = 1000.0;

Eigen::Isometry3d planarIsometry(double x, double y, double phi) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, 0.0);
  return t;
}

// A robot movement's increment into inc, or why its pose change cannot be used (a coordinate
// not finite: the robot's pose would be NaN from there on; a move longer than kMaxMovementM).
// "" with inc unset for anything else (another action, a 2D movement without a pose change).
std::string movementIncrement(const mrpt::obs::CAction& a,
                              std::optional<Eigen::Isometry3d>& inc) {
  std::vector<double> v;
  std::string names;
  if (const auto* m3 = dynamic_cast<const mrpt::obs::CActionRobotMovement3D*>(&a)) {
    const mrpt::poses::CPose3D& p = m3->poseChange.mean;
    v = {p.x(), p.y(), p.z(), p.yaw(), p.pitch(), p.roll()};
    names = "(x, y, z, yaw, pitch, roll)";
    inc = toIsometry(p);
  } else if (const auto* m2 = dynamic_cast<const mrpt::obs::CActionRobotMovement2D*>(&a)) {
    if (!m2->poseChange) return "";
    mrpt::poses::CPose2D p;
    try {
      p = m2->poseChange->getMeanVal();
    } catch (const std::exception& e) {  // (MRPT's averages throw on no samples)
      return "its pose distribution has no mean (" + describeReadError(e.what()) + ")";
    }
    v = {p.x(), p.y(), p.phi()};
    names = "(x, y, phi)";
    inc = planarIsometry(p.x(), p.y(), p.phi());
  } else {
    return "";
  }
  std::ostringstream os;
  if (std::all_of(v.begin(), v.end(), [](double d) { return std::isfinite(d); })) {
    const double move = std::hypot(v[0], v[1], v.size() == 6 ? v[2] : 0.0);
    if (move <= kMaxMovementM) return "";
    os << "its pose change moves the robot " << move << " m (more than " << kMaxMovementM
       << " m between two observations)";
  } else {
    os << "its pose change " << names << " = (";
    for (std::size_t i = 0; i < v.size(); ++i) os << (i ? ", " : "") << v[i];
    os << ") is not finite";
  }
  inc.reset();
  return os.str();
}


}  // namespace

struct RawlogReader::Impl {
  std::string path;
  std::string images_dir;
  mrpt::io::CFileGZInputStream in;
  // MRPT reads through it; the pre-check looks at the next object's bytes before MRPT does.
  std::unique_ptr<detail::LookaheadStream> lookahead;
  mrpt::serialization::CArchive::UniquePtr archive;
  RawlogStats stats;
  bool seen_frames = false, seen_bare_observations = false;
  bool finished = false;
  std::string failure;  // set once a read failed: later calls throw it again
  std::size_t failure_object = 0;
  uint64_t failure_offset = 0;
  std::string failure_reason;

  struct Pending {
    std::shared_ptr<mrpt::obs::CObservation> obs;
    std::size_t object_index;
  };
  std::deque<Pending> pending;                 // observations of the last sensory frame
  std::optional<Eigen::Isometry3d> increment;  // odometry not yet attached to an observation

  void skip(const std::string& reason) { ++stats.skipped[reason]; }

  void addIncrement(const Eigen::Isometry3d& inc) {
    increment = increment ? Eigen::Isometry3d(*increment * inc) : inc;
    ++stats.odometry_actions;
  }

  // The actions of one object (a collection's, or one bare action): every movement's pose change
  // checked first (one that cannot be used is damage at the object, at object_index and
  // position), then the first movement's increment used and the rest counted.
  void handleActions(const std::vector<const mrpt::obs::CAction*>& acts, bool in_collection,
                     std::size_t object_index, uint64_t position) {
    std::vector<std::optional<Eigen::Isometry3d>> inc(acts.size());
    for (std::size_t i = 0; i < acts.size(); ++i) {
      if (!acts[i]) continue;
      const std::string why = movementIncrement(*acts[i], inc[i]);
      if (why.empty()) continue;
      const std::string where = in_collection ? " (action " + std::to_string(i + 1) + " of " +
                                                    std::to_string(acts.size()) +
                                                    " in a CActionCollection)"
                                              : "";
      fail(object_index, position,
           "corrupt " + detail::shortClassName(*acts[i]) + where + ": " + why);
    }
    bool used = false;
    for (std::size_t i = 0; i < acts.size(); ++i) {
      const mrpt::obs::CAction* a = acts[i];
      if (!a) {
        skip("null action in a CActionCollection");
      } else if (!dynamic_cast<const mrpt::obs::CActionRobotMovement3D*>(a) &&
                 !dynamic_cast<const mrpt::obs::CActionRobotMovement2D*>(a)) {
        skip("action " + detail::shortClassName(*a) + " (not a robot movement)");
      } else if (used) {
        skip("extra robot movement in one CActionCollection (the first is used)");
      } else if (!inc[i]) {
        skip("CActionRobotMovement2D without a pose change");
      } else {
        addIncrement(*inc[i]);
        used = true;
      }
    }
  }

  void handleFrame(const std::vector<mrpt::obs::CObservation::Ptr>& observations,
                   std::size_t object_index) {
    ++stats.sensory_frames;
    seen_frames = true;
    if (observations.empty()) skip("empty CSensoryFrame");
    for (const auto& obs : observations) {
      if (!obs) {
        skip("null observation in a CSensoryFrame");
        continue;
      }
      pending.push_back({obs, object_index});
    }
  }

  void handleCollection(const std::vector<const mrpt::obs::CAction*>& actions,
                        std::size_t object_index, uint64_t position) {
    ++stats.action_collections;
    seen_frames = true;
    if (actions.empty()) skip("empty CActionCollection");
    handleActions(actions, true, object_index, position);
  }

  void handleObject(const mrpt::serialization::CSerializable::Ptr& o, std::size_t object_index,
                    uint64_t position) {
    if (!o) {
      skip("null object");
      return;
    }
    if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(o)) {
      handleFrame({sf->begin(), sf->end()}, object_index);
      return;
    }
    if (auto acts = std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(o)) {
      std::vector<const mrpt::obs::CAction*> list;
      for (const auto& a : *acts) list.push_back(a ? a.get() : nullptr);
      handleCollection(list, object_index, position);
      return;
    }
    if (auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(o)) {
      seen_bare_observations = true;
      pending.push_back({obs, object_index});
      return;
    }
    if (auto act = std::dynamic_pointer_cast<mrpt::obs::CAction>(o)) {
      // A bare action outside a collection: use a movement, count anything else.
      seen_frames = true;
      handleActions({act.get()}, false, object_index, position);
      return;
    }
    skip("top-level " + detail::shortClassName(*o) +
         " (not an action, sensory frame or observation)");
  }

  // A sensory frame or action collection read as MRPT reads it, but one element at a time, each
  // checked at its own start (a check of the whole container would stop at the first element of
  // a layout it does not know: what follows would reach MRPT unchecked), then handled.
  void readContainer(const detail::ContainerHead& head, std::size_t object_index,
                     uint64_t position) {
    std::vector<std::uint8_t> head_bytes(head.bytes);  // the header and count, peeked
    archive->ReadBuffer(head_bytes.data(), head_bytes.size());
    const char* kind = head.frame ? "observation" : "action";
    std::vector<mrpt::serialization::CSerializable::Ptr> elements(head.count);
    for (std::uint32_t i = 0; i < head.count; ++i) {
      const std::string why = detail::precheckNextElement(*lookahead, head, i);
      if (!why.empty()) fail(object_index, position, why);
      *archive >> elements[i];
      const auto* e = elements[i].get();
      const bool observation = dynamic_cast<const mrpt::obs::CObservation*>(e) != nullptr;
      const bool action = dynamic_cast<const mrpt::obs::CAction*>(e) != nullptr;
      const bool fits = !e || (head.frame ? observation : action);
      if (!fits) {
        fail(object_index, position,
             std::string("corrupt ") + (head.frame ? "CSensoryFrame" : "CActionCollection") +
                 ": " + kind + " " + std::to_string(i + 1) + " of " +
                 std::to_string(head.count) + " is a " + detail::shortClassName(*elements[i]) +
                 ", not an " + kind);
      }
    }
    std::uint8_t end = 0x88;
    if (head.has_end_flag) {
      if (!lookahead->peek(0, &end, 1)) {
        fail(object_index, position,
             detail::truncatedAt(lookahead->getPosition()) + " (before its end flag)");
      }
      archive->ReadBuffer(&end, 1);
    }
    if (end != 0x88) {
      fail(object_index, position,
           std::string("corrupt ") + (head.frame ? "CSensoryFrame" : "CActionCollection") +
               ": no end flag after its " + std::to_string(head.count) + " " + kind +
               (head.count == 1 ? "" : "s"));
    }
    if (head.frame) {
      std::vector<mrpt::obs::CObservation::Ptr> observations;
      for (const auto& e : elements) {
        auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(e);
        // (A version-0 frame's timestamp is its observations': MRPT sets it on each.)
        if (obs && head.version == 0) {
          obs->timestamp = mrpt::Clock::time_point(mrpt::Clock::duration(head.timestamp));
        }
        observations.push_back(std::move(obs));
      }
      handleFrame(observations, object_index);
    } else {
      std::vector<const mrpt::obs::CAction*> actions;
      for (const auto& e : elements) actions.push_back(dynamic_cast<const mrpt::obs::CAction*>(e.get()));
      handleCollection(actions, object_index, position);
    }
  }

  [[noreturn]] void fail(std::size_t object_index, uint64_t offset, const std::string& why) {
    std::ostringstream os;
    os << "rawlog " << path << ": cannot read object #" << object_index << " (at byte " << offset
       << " of the decompressed stream): " << why << "; read before it: " << stats.objects
       << " objects, " << stats.entries << " observations";
    failure = os.str();
    failure_object = object_index;
    failure_offset = offset;
    failure_reason = why;
    finished = true;
    throw RawlogError(failure, path, object_index, offset, why);
  }
};

RawlogReader::RawlogReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  // Observation classes register when their module loads; a program that links mrpt-maps but
  // calls nothing in it would not know CObservationPointCloud (and friends) when reading.
  mrpt::obs::registerAllClasses_mrpt_obs();
  mrpt::maps::registerAllClasses_mrpt_maps();
  impl_->path = path;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw std::runtime_error("rawlog " + path + ": not found");
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw std::runtime_error("rawlog " + path + ": not a regular file");
  }
  if (!std::ifstream(path).good()) throw std::runtime_error("rawlog " + path + ": unreadable");
  if (!impl_->in.open(path)) throw std::runtime_error("rawlog " + path + ": cannot be opened");
  impl_->lookahead = std::make_unique<detail::LookaheadStream>(impl_->in);
  impl_->archive = mrpt::serialization::archiveUniquePtrFrom(*impl_->lookahead);
  impl_->images_dir = detectImagesDirectory(path);
  mrpt::img::CImage::setImagesPathBase(impl_->images_dir);
}

RawlogReader::~RawlogReader() = default;

bool RawlogReader::next(RawlogEntry& entry) {
  Impl& d = *impl_;
  for (;;) {
    if (!d.pending.empty()) {
      Impl::Pending p = std::move(d.pending.front());
      d.pending.pop_front();
      entry.index = d.stats.entries++;
      entry.object_index = p.object_index;
      entry.timestamp_s = detail::toSeconds(p.obs->timestamp);
      entry.odometry_increment = d.increment;
      d.increment.reset();
      ++d.stats.entries_by_class[detail::shortClassName(*p.obs)];
      entry.observation = std::move(p.obs);
      return true;
    }
    if (!d.failure.empty()) {
      throw RawlogError(d.failure, d.path, d.failure_object, d.failure_offset, d.failure_reason);
    }
    if (d.finished) return false;

    const std::size_t object_index = d.stats.objects;
    const uint64_t position = d.lookahead->getPosition();
    mrpt::serialization::CSerializable::Ptr object;
    std::string impossible;
    bool read_as_container = false;
    try {
      // A container's elements are checked one at a time as they are read (a walk of the whole
      // container first would decode each JPEG in it once more); any other object whole.
      detail::ContainerHead head;
      if (detail::peekContainerHead(*d.lookahead, head)) {
        impossible = detail::precheckContainerHead(*d.lookahead, head);
        if (impossible.empty()) {
          d.readContainer(head, object_index, position);
          read_as_container = true;
        }
      } else {
        impossible = detail::precheckNextObject(*d.lookahead);
        if (impossible.empty()) *d.archive >> object;
      }
    } catch (const RawlogError&) {
      throw;
    } catch (const mrpt::serialization::CExceptionEOF& e) {
      if (d.lookahead->getPosition() != position) {
        d.fail(object_index, position,
               "truncated, the file ends inside it (" + describeReadError(e.what()) + ")");
      }
      d.finished = true;
      if (d.increment) d.skip("odometry at the end of the file with no observation after it");
      d.increment.reset();
      return false;
    } catch (const std::exception& e) {
      d.fail(object_index, position, "corrupt or truncated (" + describeReadError(e.what()) + ")");
    }
    if (!impossible.empty()) d.fail(object_index, position, impossible);
    // (may find the object's actions damaged)
    if (!read_as_container) d.handleObject(object, object_index, position);
    ++d.stats.objects;
  }
}

const RawlogStats& RawlogReader::stats() const { return impl_->stats; }

RawlogLayout RawlogReader::layout() const {
  if (impl_->seen_frames && impl_->seen_bare_observations) return RawlogLayout::Mixed;
  if (impl_->seen_frames) return RawlogLayout::ActionsAndFrames;
  if (impl_->seen_bare_observations) return RawlogLayout::ObservationsOnly;
  return RawlogLayout::Empty;
}

const std::string& RawlogReader::path() const { return impl_->path; }
const std::string& RawlogReader::imagesDirectory() const { return impl_->images_dir; }

RawlogStats scanRawlog(const std::string& path) {
  RawlogReader reader(path);
  RawlogEntry entry;
  while (reader.next(entry)) {
  }
  return reader.stats();
}

}  // namespace upd::mrpt_bridge
