#include "upd/nav/scene_objects.h"

#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/rtti/CObject.h>

#include <stdexcept>

namespace upd::nav {

std::shared_ptr<mrpt::opengl::CSetOfLines> newSetOfLines() {
  auto lines = std::dynamic_pointer_cast<mrpt::opengl::CSetOfLines>(
      mrpt::rtti::classFactory("mrpt::opengl::CSetOfLines"));
  if (!lines) throw std::logic_error("MRPT's class factory does not know mrpt::opengl::CSetOfLines");
  return lines;
}

}  // namespace upd::nav
