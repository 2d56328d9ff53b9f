#include "output_folder.h"

#include <system_error>

namespace upd::app {

namespace fs = std::filesystem;

OutputFolder::OutputFolder(const fs::path& dir) {
  for (fs::path p = fs::absolute(dir).lexically_normal(); p.has_relative_path() && !fs::exists(p);
       p = p.parent_path()) {
    if (!p.has_filename()) continue;  // "out/" normalizes to a trailing empty name
    created_.push_back(p);
  }
  fs::create_directories(dir);
}

OutputFolder::~OutputFolder() {
  for (const fs::path& p : created_) {
    std::error_code ec;
    fs::remove(p, ec);  // fails, and leaves it, when something was written into it
  }
}

}  // namespace upd::app
