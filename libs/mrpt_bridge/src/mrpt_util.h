// Small helpers shared by the bridge's sources (private: not installed, not included by users).
#pragma once

#include <mrpt/core/Clock.h>
#include <mrpt/rtti/CObject.h>

#include <string>

namespace upd::mrpt_bridge::detail {

/// "mrpt::obs::CObservation3DRangeScan" -> "CObservation3DRangeScan".
std::string shortClassName(const mrpt::rtti::CObject& object);

/// Seconds since the UNIX epoch; NaN for INVALID_TIMESTAMP.
double toSeconds(const mrpt::Clock::time_point& t);

/// MRPT exception texts span many lines (message, location, backtrace): keeps the "Message:"
/// lines, joined, with non-printable bytes replaced (a corrupt file yields garbage class names).
std::string condenseMessage(const std::string& what);

}  // namespace upd::mrpt_bridge::detail
