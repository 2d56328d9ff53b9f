// `upd playback` stopped by Ctrl-C (SIGINT) or SIGTERM: a long simulated run is played with
// --ply, the signal is sent once the first frames' files are written, and the run must stop
// after the frame in progress with exit 3, summary.json saying "end": "interrupted", every
// output complete and readable, no temporary file left, and the fused maps byte for byte those
// of a clean run over the same frames (--to).
#include "run_upd.h"
#include "temp_dir.h"

#include "upd/io/cloud_io.h"
#include "upd/io/ros_map.h"
#include "upd/maps/traversability_octree.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <thread>

extern char** environ;

namespace upd {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using test::CmdResult;
using test::runUpd;

const std::string kConfig = std::string(UPD_SOURCE_DIR) + "/config/dune-kinect.ini";
constexpr int kFrames = 30;
const char* const kMaps[] = {"map.png", "map.pgm", "map.yaml", "map.ot", "map.bt",
                             "map_colour.ot", "map_traversability.ot"};

// Starts `upd playback` on rawlog with --ply, waits until frame `after` is written, sends signo,
// and returns the exit status (-1 unless it exited normally).
int playAndSignal(const fs::path& rawlog, const fs::path& out, int after, int signo) {
  const std::vector<std::string> args = {UPD_BINARY, "playback", rawlog.string(), "--config",
                                         kConfig, "--output", out.string(), "--quiet", "--ply"};
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, UPD_BINARY, nullptr, nullptr, argv.data(), environ) != 0) return -2;
  char name[32];
  std::snprintf(name, sizeof name, "%06d.ply", after);
  const fs::path marker = out / "frames" / name;
  int status = 0;
  // The frame files are written atomically: once one exists, that frame is done.
  while (!fs::exists(marker)) {
    if (waitpid(pid, &status, WNOHANG) == pid) return -3;  // ended before the signal
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(pid, signo);
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class PlaybackInterrupt : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir("run");
    const CmdResult sim = runUpd("simulate --world mixed --frames " + std::to_string(kFrames) +
                                 " --output " + rawlog().string());
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
  }
  static void TearDownTestSuite() { delete dir_; }
  static fs::path rawlog() { return dir_->path() / "mixed.rawlog"; }

  // Every output is complete and readable, and the maps equal a clean run of the same frames.
  void expectValidPartialOutputs(const fs::path& out) {
    const json s = json::parse(std::ifstream(out / "summary.json"));
    EXPECT_EQ(s["end"], "interrupted");
    const std::size_t processed = s["frames_processed"].get<std::size_t>();
    ASSERT_GE(processed, 2u);
    EXPECT_LT(processed, std::size_t{kFrames}) << "the run was not stopped early";
    EXPECT_EQ(s["frames_read"].get<std::size_t>(), processed);
    EXPECT_FALSE(s.contains("damage"));
    std::size_t plys = 0;
    for (const auto& e : fs::directory_iterator(out / "frames")) {
      EXPECT_NO_THROW(io::readPly(e.path().string())) << e.path();
      ++plys;
    }
    EXPECT_EQ(plys, processed);
    for (const auto& e : fs::recursive_directory_iterator(out)) {
      EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
    }
    EXPECT_NO_THROW(io::readRosMap((out / "map.yaml").string()));
    EXPECT_TRUE(maps::readTraversabilityOt((out / "map_traversability.ot").string()));
    EXPECT_GT(fs::file_size(out / "map.3Dscene"), 0u);

    const fs::path ref = out.string() + "_ref";
    const CmdResult r = runUpd("playback " + rawlog().string() + " --config " + kConfig +
                               " --quiet --output " + ref.string() + " --to " +
                               std::to_string(processed - 1));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(json::parse(std::ifstream(ref / "summary.json"))["end"], "complete");
    for (const char* f : kMaps) {
      EXPECT_TRUE(test::readFileBytes(out / f) == test::readFileBytes(ref / f)) << f;
    }
  }

  static test::TempDir* dir_;
};

test::TempDir* PlaybackInterrupt::dir_ = nullptr;

TEST_F(PlaybackInterrupt, CtrlCWritesTheMapsOfTheFramesProcessed) {
  const fs::path out = dir_->path() / "sigint";
  ASSERT_EQ(playAndSignal(rawlog(), out, 1, SIGINT), 3);
  expectValidPartialOutputs(out);
}

TEST_F(PlaybackInterrupt, SigtermToo) {
  const fs::path out = dir_->path() / "sigterm";
  ASSERT_EQ(playAndSignal(rawlog(), out, 1, SIGTERM), 3);
  expectValidPartialOutputs(out);
}

TEST(PlaybackInterruptHelp, DocumentsCtrlCAndTheExitStatus) {
  const CmdResult r = runUpd("playback --help");
  EXPECT_NE(r.output.find("Ctrl-C"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"end\": \"interrupted\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("or the run was interrupted"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace upd
