#pragma once
// MRPT scene objects that must be made by MRPT's own code.

#include <memory>

namespace mrpt::opengl {
class CSetOfLines;
}

namespace upd::nav {

// A new, empty CSetOfLines made (and so destroyed) by MRPT's class factory.
// MRPT 2.5.8's headers declare CSetOfLines' CRenderizableShaderPoints base 32-byte aligned, but
// GCC 12 lays that base out 16 bytes off the 32-byte grid inside CSetOfLines: the destructor that
// CSetOfLines::Create() instantiates in the caller is a member call on a misaligned object
// (UBSan, scripts/sanitize.sh). The object the class factory makes has the same layout, but its
// destructor is compiled inside libmrpt-opengl. Throws std::logic_error if the factory does not
// know the class.
std::shared_ptr<mrpt::opengl::CSetOfLines> newSetOfLines();

}  // namespace upd::nav
