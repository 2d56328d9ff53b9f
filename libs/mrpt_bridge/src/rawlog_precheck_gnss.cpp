// The messages of a CObservationGPS, walked as MRPT 2.5.8's gnss_message::readAndBuildFromStream()
// reads them: a 32-bit message type, then the message. Most types have one size whatever they hold
// (a binary block: its 32-bit length, which MRPT requires to be the type's, then the block); their
// sizes are taken from MRPT itself, by writing a message of each type it builds. Five hold lists
// MRPT resizes to a count it reads: Novatel's generic frames (a body), RANGECMP (observations),
// VERSION (components) and Topcon's SATS (three lists of satellites).
#include "rawlog_precheck_cursor.h"

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/gnss_messages.h>
#include <mrpt/serialization/CArchive.h>

#include <map>
#include <memory>

namespace upd::mrpt_bridge::detail {
namespace {

namespace gnss = mrpt::obs::gnss;

constexpr Parse kRead = Parse::Read;
constexpr Parse kOther = Parse::OtherLayout;
constexpr Parse kImpossible = Parse::Impossible;

// A type of one size: the bytes after its type, and the binary block's length (0: no block).
struct FixedSize {
  std::size_t bytes = 0;
  std::uint32_t block = 0;
};

bool holdsLists(int type) {
  return type == gnss::NV_OEM6_GENERIC_FRAME || type == gnss::NV_OEM6_GENERIC_SHORT_FRAME ||
         type == gnss::NV_OEM6_RANGECMP || type == gnss::NV_OEM6_VERSION ||
         type == gnss::TOPCON_SATS;
}

// Every type MRPT's factory builds but those holding lists, with the size MRPT writes it at.
const std::map<int, FixedSize>& fixedSizes() {
  static const std::map<int, FixedSize> sizes = [] {
    std::map<int, FixedSize> out;
    for (int type = 0; type < 5000; ++type) {
      if (holdsLists(type)) continue;
      std::unique_ptr<gnss::gnss_message> m(
          gnss::gnss_message::Factory(static_cast<gnss::gnss_message_type_t>(type)));
      if (!m) continue;
      mrpt::io::CMemoryStream buffer;
      auto archive = mrpt::serialization::archiveFrom(buffer);
      m->writeToStream(archive);
      const auto* bytes = static_cast<const std::uint8_t*>(buffer.getRawBufferData());
      FixedSize size;
      size.bytes = buffer.getTotalBytesCount() - sizeof(std::int32_t);
      std::uint32_t block = 0;
      if (size.bytes >= sizeof block) {
        std::memcpy(&block, bytes + sizeof(std::int32_t), sizeof block);
        if (sizeof block + block == size.bytes) size.block = block;
      }
      out[type] = size;
    }
    return out;
  }();
  return sizes;
}

// A Novatel frame kept whole: its header, a body length MRPT resizes the body to, and then (MRPT
// 2.5.8 reads only as many bytes as the length field has) 4 bytes of the body when it has any.
Parse genericFrame(Cursor& c, std::size_t header_bytes, std::string& why) {
  c.skip(header_bytes);
  const std::uint64_t at = c.position();
  std::uint32_t n = 0;
  if (!c.value(n)) return kOther;
  if (!withinBound("Novatel frame body length", n, at, kMaxGnssFrameBytes, "bytes", why)) {
    return kImpossible;
  }
  if (n > 0) c.skip(sizeof n);
  return kRead;
}

// A Novatel log of records: its length, header and record count (MRPT refuses 2,000 or more), then
// the records.
Parse records(Cursor& c, std::size_t record_bytes) {
  c.skip(sizeof(std::uint32_t) + sizeof(gnss::nv_oem6_header_t));
  std::uint32_t n = 0;
  if (!c.value(n) || n >= 2000) return kOther;
  c.skip(std::uint64_t{n} * record_bytes);
  return kRead;
}

Parse message(Cursor& c, std::string& why) {
  std::int32_t type = 0;
  if (!c.value(type)) return kOther;
  switch (type) {
    case gnss::NV_OEM6_GENERIC_FRAME:
      return genericFrame(c, sizeof(gnss::nv_oem6_header_t), why);
    case gnss::NV_OEM6_GENERIC_SHORT_FRAME:
      return genericFrame(c, sizeof(gnss::nv_oem6_short_header_t), why);
    case gnss::NV_OEM6_RANGECMP:
      return records(c, sizeof(gnss::Message_NV_OEM6_RANGECMP::TCompressedRangeLog));
    case gnss::NV_OEM6_VERSION:
      return records(c, sizeof(gnss::Message_NV_OEM6_VERSION::TComponentVersion));
    case gnss::TOPCON_SATS: {
      // Satellite IDs, elevations and azimuths: bytes, bytes and 16-bit values.
      Parse p = checkList(c, "satellite ID count", 1, kMaxGnssSatellites, "satellites", why);
      if (p == kRead) p = checkList(c, "elevation count", 1, kMaxGnssSatellites, "satellites", why);
      if (p == kRead) p = checkList(c, "azimuth count", 2, kMaxGnssSatellites, "satellites", why);
      return p;
    }
    default:
      break;
  }
  const auto& sizes = fixedSizes();
  const auto it = sizes.find(type);
  if (it == sizes.end()) return kOther;  // MRPT does not know the type: it says so
  if (it->second.block != 0) {
    std::uint32_t block = 0;
    if (!c.value(block) || block != it->second.block) return kOther;  // MRPT refuses it
    c.skip(block);
  } else {
    c.skip(it->second.bytes);
  }
  return kRead;
}

}  // namespace

Parse checkList(Cursor& c, const char* field, std::size_t element_bytes, std::uint64_t max,
                const char* unit, std::string& why) {
  const std::uint64_t at = c.position();
  std::uint32_t n = 0;
  if (!c.value(n)) return kOther;
  if (!withinBound(field, n, at, max, unit, why)) return kImpossible;
  c.skip(std::uint64_t{n} * element_bytes);
  return kRead;
}

Parse checkGnssMessages(Cursor& c, std::uint32_t count, std::string& why) {
  Parse p = kRead;
  for (std::uint32_t i = 0; i < count && p == kRead; ++i) p = message(c, why);
  return p;
}

}  // namespace upd::mrpt_bridge::detail
