#include "upd/core/version.h"

namespace upd::core {

const char* version() { return UPD_NAV_VERSION; }

}  // namespace upd::core
