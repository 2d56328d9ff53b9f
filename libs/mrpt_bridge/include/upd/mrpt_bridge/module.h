// The project's modules: the parts whose libraries are heavy to load (MRPT's hwdrivers and gui
// pull in ~170 more shared libraries, ~0.25 s at every start of `upd`) are shared objects of
// their own, loaded when first used. A module sits beside the library that loads it (the build
// tree and the installed lib/ alike) and has one entry point, a function with C linkage.
// In a static build there are no modules: their code is part of the library that uses it.
#pragma once

namespace upd::mrpt_bridge {

/// The address of `symbol` in the module `file` (e.g. "libupd_nav_viewer.so"), loaded (once)
/// from the folder of the shared object that holds `beside` (an address in the caller's own
/// library). Throws std::runtime_error naming the file and the loader's reason when it cannot
/// be loaded or lacks the symbol.
void* moduleSymbol(const char* file, const char* symbol, const void* beside);

/// A module's entry point, an object of type Entry with C linkage, found by moduleSymbol on
/// the first call and kept (one module per Entry type).
template <class Entry>
const Entry& moduleEntry(const char* file, const char* symbol, const void* beside) {
  static const Entry* const entry = static_cast<const Entry*>(moduleSymbol(file, symbol, beside));
  return *entry;
}

}  // namespace upd::mrpt_bridge
