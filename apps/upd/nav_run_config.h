// The two config files of every command that drives the robot (`navigate`, `bench-nav`, `live`,
// `ros`, `calibrate-mount`): the robot config (`--config`) and the navigation config
// (`--nav-config`), each the shipped file when not given.
#pragma once

#include "cli.h"

#include "upd/nav/nav_config.h"

#include <string>

namespace upd::app {

struct NavConfigPaths {
  std::string robot;  ///< --config, or <config dir>/dune-kinect.ini
  std::string nav;    ///< --nav-config, or <config dir>/dune-nav.ini
};

/// The paths given by --config and --nav-config; the shipped configs are looked up only for the
/// files not given.
NavConfigPaths navConfigPaths(const Args& args);

/// Checks the robot config strictly (an unknown section or key is an error, as in every
/// command), then reads the navigator's view of both files.
nav::NavConfig loadNavConfigs(const NavConfigPaths& paths);

}  // namespace upd::app
