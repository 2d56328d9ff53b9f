// The modules' loader (module.h): a module beside the library that loads it, and one line
// naming the file when it cannot be loaded.
#include "upd/mrpt_bridge/module.h"
#include "error_of.h"

#include <gtest/gtest.h>

#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>
#include <string>

namespace {

// An address inside libupd_mrpt_bridge, and that library's folder ("" in a static build).
const void* bridgeAddress() { return reinterpret_cast<const void*>(&upd::mrpt_bridge::moduleSymbol); }

std::string bridgeFolder() {
  Dl_info info{};
  if (dladdr(bridgeAddress(), &info) == 0 || info.dli_fname == nullptr) return "";
  const std::filesystem::path lib(info.dli_fname);
  return lib.filename().string().rfind("libupd_mrpt_bridge", 0) == 0 ? lib.parent_path().string() : "";
}

std::string errorOf(const char* file, const char* symbol) {
  return upd::test::errorOf<std::runtime_error>(
      [&] { upd::mrpt_bridge::moduleSymbol(file, symbol, bridgeAddress()); });
}

}  // namespace

TEST(Module, AMissingModuleIsOneLineNamingItsPath) {
  const std::string folder = bridgeFolder();
  if (folder.empty()) GTEST_SKIP() << "a static build: the loader has no folder to look in";
  const std::string e = errorOf("libupd_no_such_module.so", "upd_entry");
  EXPECT_EQ(e.rfind("module " + folder + "/libupd_no_such_module.so: cannot be loaded: ", 0), 0u) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

TEST(Module, TheSensorsModuleIsFoundBesideTheBridge) {
  const std::string folder = bridgeFolder();
  if (folder.empty() || !std::filesystem::exists(folder + "/libupd_mrpt_sensors.so")) {
    GTEST_SKIP() << "a static build: the sensors are part of the bridge";
  }
  EXPECT_NE(upd::mrpt_bridge::moduleSymbol("libupd_mrpt_sensors.so", "upd_mrpt_sensor_drivers",
                                           bridgeAddress()),
            nullptr);
  // Loaded once: asked again, the same entry point.
  EXPECT_EQ(upd::mrpt_bridge::moduleSymbol("libupd_mrpt_sensors.so", "upd_mrpt_sensor_drivers",
                                           bridgeAddress()),
            upd::mrpt_bridge::moduleSymbol("libupd_mrpt_sensors.so", "upd_mrpt_sensor_drivers",
                                           bridgeAddress()));
  const std::string e = errorOf("libupd_mrpt_sensors.so", "upd_no_such_entry");
  EXPECT_EQ(e, "module " + folder + "/libupd_mrpt_sensors.so: has no entry point upd_no_such_entry");
}
