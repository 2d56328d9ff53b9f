// The `upd` subcommands. Each takes its arguments (after the subcommand name), returns the
// process exit code and throws on error; main prints the message.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace upd::app {

struct Command {
  const char* name;
  const char* summary;
  const char* usage;
  int (*run)(const std::vector<std::string>& args);
};

int runAnalyze(const std::vector<std::string>& args);
int runScene(const std::vector<std::string>& args);
int runParams(const std::vector<std::string>& args);
int runSimulate(const std::vector<std::string>& args);
int runPlayback(const std::vector<std::string>& args);
int runNavigate(const std::vector<std::string>& args);
int runBenchNav(const std::vector<std::string>& args);
int runLive(const std::vector<std::string>& args);
int runMap(const std::vector<std::string>& args);
int runCalibrateMount(const std::vector<std::string>& args);
int runRos(const std::vector<std::string>& args);
int runRender(const std::vector<std::string>& args);
int runHistogram(const std::vector<std::string>& args);
int runBaseline(const std::vector<std::string>& args);
int runView(const std::vector<std::string>& args);
int runEvaluate(const std::vector<std::string>& args);
int runTrain(const std::vector<std::string>& args);

extern const char* const kAnalyzeUsage;
extern const char* const kSceneUsage;
extern const char* const kParamsUsage;
extern const char* const kSimulateUsage;
extern const char* const kPlaybackUsage;
extern const char* const kNavigateUsage;
extern const char* const kBenchNavUsage;
extern const char* const kLiveUsage;
extern const char* const kMapUsage;
extern const char* const kCalibrateMountUsage;
extern const char* const kRosUsage;
extern const char* const kRenderUsage;
extern const char* const kHistogramUsage;
extern const char* const kBaselineUsage;
extern const char* const kViewUsage;
extern const char* const kEvaluateUsage;
extern const char* const kTrainUsage;

/// Makes `[ClassifyParams] classifier = FILE` loadable (libs/learn, when built).
void registerClassifierLoader();

/// The --size WxH option of `upd render` and `upd histogram`; throws UsageError naming it.
std::pair<int, int> parseImageSize(const std::string& s);

}  // namespace upd::app
