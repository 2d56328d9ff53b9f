#include "run_config.h"

#include "upd/mrpt_bridge/ini_params.h"

namespace upd::app {

RunConfig loadRunConfig(const std::string& path) {
  RunConfig c;
  mrpt_bridge::IniReader ini(path);
  forEachSection(c, [&](const char* name, const char*, auto& params) { ini.read(name, params); });
  mrpt_bridge::readClassifier(ini, c.observer.pipeline);
  ini.checkAllKeysKnown();
  try {
    c.observer.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("config file " + path + ": " + e.what());
  }
  return c;
}

}  // namespace upd::app
