// `upd evaluate`: the UPD, its baselines and the learned classifier scored against labelled
// data (generated scenes and views, real frames with geometric labels, semantic LiDAR).
#include "cli.h"
#include "commands.h"
#include "evaluate_report.h"

#include "upd/core/stopwatch.h"
#include "upd/nav/nav_config.h"

#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

namespace upd::app {

const char* const kEvaluateUsage =
    "usage: upd evaluate [INPUT...] --output DIR [options]\n"
    "  Scores the UPD (zeta and slope), zeta alone, the slope of r alone, the roughness and\n"
    "  inclination indices, the normal's slope, the height range and the learned classifier\n"
    "  against labelled clouds: precision, recall and F1 of non-traversable for each rule, the\n"
    "  ROC curve and AUC of each score, per point and per map cell, at several d_m.\n"
    "  Data: the generated scenes (with and without noise) and simulated Kinect views (with\n"
    "  and without the Kinect noise model) of the held-out split, the real RGB-D frames of the\n"
    "  shared data with geometric labels (docs/EVALUATION.md), and INPUT: SemanticKITTI or\n"
    "  RELLIS-3D folders or NNNNNN.bin scans with their NNNNNN.label files.\n\n"
    "options:\n"
    "  --output DIR          evaluation.md, evaluation.json, roc_<group>_d<d_m>.png (required)\n"
    "  --class-map FILE      class id -> traversability for INPUT (share/class_maps/\n"
    "                        semantic-kitti.txt, rellis-3d.txt)\n"
    "  --radius-m LIST       d_m values, comma-separated (default 0.3,0.5,1.0)\n"
    "  --cell-m C            map cell of the per-cell tables [m] (default 0.2)\n"
    "  --config FILE.ini     score every cloud with this config (default: the shipped\n"
    "                        dune-kinect.ini for depth data, lidar.ini for LiDAR)\n"
    "  --classifier FILE     learned classifier (default: the shipped\n"
    "                        models/traversability.yml.gz when this upd has libs/learn)\n"
    "  --no-classifier       score without it\n"
    "  --shared-data DIR     real frames from DIR (default: $UPD_SHARED_DATA_DIR,\n"
    "                        ../shared/data or /work/shared/data when present)\n"
    "  --no-shared           no real frames\n"
    "  --no-generated        no generated scenes and views\n"
    "  --all-scenes          also score the scenes the shipped classifier was trained on\n"
    "  --max-scans N         scans per semantic folder, evenly spaced (default 20)\n";

namespace {

std::vector<double> parseRadii(const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !(v > 0) || v > 5) {
      throw UsageError("--radius-m '" + text + "': expected d_m values in (0, 5] m, comma-separated");
    }
    out.push_back(v);
  }
  return out;
}

std::string commandLine(const std::vector<std::string>& argv) {
  std::string s = "upd evaluate";
  for (const auto& a : argv) s += " " + a;
  return s;
}

// The --classifier file, the shipped model, or none.
std::string classifierPath(const Args& args, std::vector<std::string>& notes) {
  if (args.flag("--no-classifier")) return "";
  if (const auto f = args.str("--classifier")) return *f;
  const auto shipped = std::filesystem::path(nav::defaultDataDir()) / "models" / "traversability.yml.gz";
  if (!std::filesystem::exists(shipped)) {
    notes.push_back("no learned classifier: " + shipped.string() + " not found");
    return "";
  }
  return shipped.string();
}

DataOptions dataOptions(const Args& args, std::vector<std::string>& notes) {
  DataOptions d;
  d.generated = !args.flag("--no-generated");
  if (!args.flag("--no-shared")) {
    d.shared_dir = args.str("--shared-data").value_or(findSharedDataDir());
    if (d.shared_dir.empty()) {
      notes.push_back("real frames skipped: no shared data folder ($UPD_SHARED_DATA_DIR, "
                      "../shared/data, /work/shared/data)");
    } else if (!std::filesystem::is_directory(d.shared_dir)) {
      throw std::runtime_error("--shared-data '" + d.shared_dir + "': no such folder");
    }
  }
  d.semantic_inputs = args.positionals();
  d.class_map = args.str("--class-map").value_or("");
  d.max_scans = args.integer("--max-scans").value_or(20);
  return d;
}

}  // namespace

int runEvaluate(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--output", "--class-map", "--radius-m", "--cell-m", "--config",
                   "--classifier", "--shared-data", "--max-scans"},
                  {"--no-classifier", "--no-shared", "--no-generated", "--all-scenes"});
  const auto out_dir = args.str("--output");
  if (!out_dir) throw UsageError("--output DIR is required");
  EvaluationReport rep;
  rep.command = commandLine(argv);
  if (const auto r = args.str("--radius-m")) rep.settings.radii_m = parseRadii(*r);
  rep.settings.cell_m = args.number("--cell-m").value_or(0.2);
  if (!(rep.settings.cell_m > 0)) throw UsageError("--cell-m must be > 0");
  rep.settings.config = args.str("--config").value_or("");
  rep.classifier_path = classifierPath(args, rep.notes);
  if (!rep.classifier_path.empty()) {
    rep.settings.classifier = core::loadPointLabeler(rep.classifier_path);
    rep.settings.features = rep.settings.classifier->featureParams();
  }
  const DataOptions data = dataOptions(args, rep.notes);
  const bool all_scenes = args.flag("--all-scenes");

  std::map<std::string, std::size_t> index;
  std::vector<GroupPool> pools;
  std::vector<std::vector<std::string>> names;
  std::size_t training_skipped = 0;
  forEachLabelledCloud(data, [&](LabelledCloud& c) {
    if (c.trains_shipped_model && !all_scenes) {
      ++training_skipped;
      return;
    }
    core::Stopwatch sw;
    const ProcessedCloud pc = processCloud(c, rep.settings);
    const auto [it, added] = index.emplace(c.group, pools.size());
    if (added) {
      pools.emplace_back(c.group);
      names.emplace_back();
    }
    pools[it->second].add(pc, rep.settings);
    names[it->second].push_back(c.name);
    std::printf("%s: %zu points scored (%.0f ms)\n", c.name.c_str(), pc.cloud.size(), sw.elapsedMs());
    std::fflush(stdout);
  }, rep.notes);
  if (training_skipped) {
    rep.notes.push_back(std::to_string(training_skipped) +
                        " generated clouds the shipped classifier was trained on not scored (--all-scenes scores them)");
  }
  if (pools.empty()) throw std::runtime_error("no labelled data to evaluate");
  for (std::size_t g = 0; g < pools.size(); ++g) {
    rep.groups.push_back({pools[g].group(), pools[g].clouds(), pools[g].points(), pools[g].cells(),
                          names[g], pools[g].pointResults(), pools[g].cellResults()});
  }
  writeEvaluation(rep, *out_dir);
  std::printf("evaluation of %zu groups written to %s/evaluation.md\n", rep.groups.size(),
              out_dir->c_str());
  return 0;
}

}  // namespace upd::app
