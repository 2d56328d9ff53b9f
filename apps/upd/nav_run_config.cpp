#include "nav_run_config.h"

#include "run_config.h"

namespace upd::app {

NavConfigPaths navConfigPaths(const Args& args) {
  return {args.str("--config").value_or(nav::defaultConfigDir() + "/dune-kinect.ini"),
          args.str("--nav-config").value_or(nav::defaultConfigDir() + "/dune-nav.ini")};
}

nav::NavConfig loadNavConfigs(const NavConfigPaths& paths) {
  loadRunConfig(paths.robot);
  return nav::loadNavConfig(paths.robot, paths.nav);
}

}  // namespace upd::app
