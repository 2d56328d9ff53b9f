#include "upd/mrpt_bridge/module.h"

#include <dlfcn.h>

#include <stdexcept>
#include <string>

namespace upd::mrpt_bridge {

void* moduleSymbol(const char* file, const char* symbol, const void* beside) {
  Dl_info info{};
  if (dladdr(beside, &info) == 0 || info.dli_fname == nullptr) {
    throw std::runtime_error(std::string("module ") + file + ": cannot tell which library loads it");
  }
  std::string path = info.dli_fname;
  const std::size_t slash = path.rfind('/');
  path = (slash == std::string::npos ? std::string() : path.substr(0, slash + 1)) + file;
  // (Kept loaded until the process ends: its objects may outlive any caller. A module loaded
  // before is found again, not loaded twice.)
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_GLOBAL);
  if (handle == nullptr) {
    const char* why = dlerror();
    throw std::runtime_error("module " + path + ": cannot be loaded: " + (why ? why : "?"));
  }
  void* entry = dlsym(handle, symbol);
  if (entry == nullptr) {
    throw std::runtime_error("module " + path + ": has no entry point " + symbol);
  }
  return entry;
}

}  // namespace upd::mrpt_bridge
