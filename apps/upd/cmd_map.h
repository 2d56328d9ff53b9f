// The subcommands of `upd map` (cmd_map.cpp dispatches): each takes the arguments after its
// name, returns the exit code and throws on error.
#pragma once

#include <string>
#include <vector>

namespace upd::app {

int runMapInfo(const std::vector<std::string>& args);
int runMapMerge(const std::vector<std::string>& args);
int runMapCrop(const std::vector<std::string>& args);

}  // namespace upd::app
