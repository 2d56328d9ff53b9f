// `upd train`: the learned traversability classifier (libs/learn) trained on the training
// split of the labelled data `upd evaluate` reads, scored on the held-out split, written
// atomically. Without libs/learn (no OpenCV ml) the command says so.
#include "cli.h"
#include "commands.h"
#include "evaluate_scores.h"

#ifdef UPD_HAVE_LEARN
#include "upd/learn/classifier.h"
#endif

#include <cstdio>
#include <limits>
#include <sstream>
#include <map>
#include <stdexcept>

namespace upd::app {

const char* const kTrainUsage =
    "usage: upd train --output MODEL.yml [INPUT...] [options]\n"
    "  Trains the learned classifier on the per-point features of the labelled clouds of the\n"
    "  training split (the scenes `upd evaluate` does not score; docs/EVALUATION.md), prints\n"
    "  its precision, recall, F1 and AUC on the held-out split, and writes the model.\n"
    "  INPUT: SemanticKITTI or RELLIS-3D folders or .bin scans, with --class-map.\n\n"
    "options:\n"
    "  --output FILE         the model: .yml, .yaml, .xml or .json, + .gz (required); it\n"
    "                        carries its checksum (a .gz gzip's too): a file cut short,\n"
    "                        changed or without it (edited by hand) is refused when read\n"
    "  --model KINDS         rtrees, boost and/or svm, comma-separated (default rtrees): each\n"
    "                        is trained and scored on the held-out split, and the one with\n"
    "                        the highest held-out F1 is written\n"
    "  --class-map FILE      class id -> traversability for INPUT\n"
    "  --config FILE.ini     process every cloud with this config (default: the shipped ones)\n"
    "  --no-generated        no generated scenes and views\n"
    "  --shared-data DIR     held-out real frames from DIR (default: as upd evaluate)\n"
    "  --no-shared           no real frames\n"
    "  --max-scans N         scans per semantic folder (default 20)\n"
    "  --trees N             random trees / weak learners (default 100)\n"
    "  --max-depth D         depth of the random trees (default 12)\n"
    "  --max-samples N       training points, half of each class at most (default 60000)\n"
    "  --seed S              sampling seed (default 1)\n";

#ifdef UPD_HAVE_LEARN

void registerClassifierLoader() { learn::registerLoader(); }

namespace {

struct Split {
  std::vector<float> features;
  std::vector<core::Label> truth;
  std::vector<std::string> group;  // per point (held-out split only)
};

void append(Split& s, const ProcessedCloud& pc, const std::string& group, bool keep_group) {
  s.features.insert(s.features.end(), pc.features.begin(), pc.features.end());
  s.truth.insert(s.truth.end(), pc.truth.begin(), pc.truth.end());
  if (keep_group) s.group.insert(s.group.end(), pc.truth.size(), group);
}

void printScores(const char* what, const std::vector<float>& p, const std::vector<core::Label>& t) {
  const core::BinaryCounts c = core::countThreshold(p, 0.5f, t);
  std::printf("  %-40s P %.3f  R %.3f  F1 %.3f  AUC %.3f  (%zu obstacle, %zu free points)\n",
              what, c.precision(), c.recall(), c.f1(), core::computeRoc(p, t).auc, c.positives(),
              c.negatives());
}

// The held-out F1 of model (NaN without held-out data), printed with each group's scores.
double printHeldOut(const learn::PointClassifier& model, const Split& test) {
  if (test.truth.empty()) {
    std::printf("no held-out data\n");
    return std::numeric_limits<double>::quiet_NaN();
  }
  const std::vector<float> p = model.probabilityOfFeatures(test.features);
  std::printf("%s, held-out split:\n", learn::toString(model.kind()));
  printScores("all", p, test.truth);
  std::map<std::string, std::pair<std::vector<float>, std::vector<core::Label>>> by_group;
  for (std::size_t i = 0; i < p.size(); ++i) {
    by_group[test.group[i]].first.push_back(p[i]);
    by_group[test.group[i]].second.push_back(test.truth[i]);
  }
  for (const auto& [g, pt] : by_group) printScores(g.c_str(), pt.first, pt.second);
  return core::countThreshold(p, 0.5f, test.truth).f1();
}

std::vector<learn::ModelKind> modelKinds(const std::string& text) {
  std::vector<learn::ModelKind> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(learn::parseModelKind(item));
  if (out.empty()) throw UsageError("--model: expected rtrees, boost or svm");
  return out;
}

learn::TrainParams trainParams(const Args& args) {
  learn::TrainParams p;
  p.trees = args.integer("--trees").value_or(p.trees);
  p.max_depth = args.integer("--max-depth").value_or(p.max_depth);
  p.max_samples = args.integer("--max-samples").value_or(p.max_samples);
  p.seed = args.integer("--seed").value_or(p.seed);
  p.validate();
  return p;
}

}  // namespace

int runTrain(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--output", "--model", "--class-map", "--config", "--shared-data", "--max-scans",
                   "--trees", "--max-depth", "--max-samples", "--seed"},
                  {"--no-generated", "--no-shared"});
  const auto out = args.str("--output");
  if (!out) throw UsageError("--output MODEL.yml is required");
  const learn::TrainParams params = trainParams(args);
  EvalSettings settings;
  settings.config = args.str("--config").value_or("");
  DataOptions data;
  data.generated = !args.flag("--no-generated");
  if (!args.flag("--no-shared")) data.shared_dir = args.str("--shared-data").value_or(findSharedDataDir());
  data.semantic_inputs = args.positionals();
  data.class_map = args.str("--class-map").value_or("");
  data.max_scans = args.integer("--max-scans").value_or(20);
  Split train, test;
  std::vector<std::string> notes;
  forEachLabelledCloud(data, [&](LabelledCloud& c) {
    const ProcessedCloud pc = processCloud(c, settings);
    append(c.held_out ? test : train, pc, c.group, c.held_out);
    std::printf("%s: %zu points (%s)\n", c.name.c_str(), pc.cloud.size(), c.held_out ? "held out" : "train");
    std::fflush(stdout);
  }, notes);
  for (const auto& n : notes) std::printf("note: %s\n", n.c_str());
  std::shared_ptr<learn::PointClassifier> model;
  double best_f1 = -1;
  for (learn::ModelKind kind : modelKinds(args.str("--model").value_or("rtrees"))) {
    learn::TrainParams p = params;
    p.kind = kind;
    auto m = learn::PointClassifier::train(train.features, train.truth, settings.features, p);
    const double f1 = printHeldOut(*m, test);
    if (!model || f1 > best_f1) {
      model = m;
      best_f1 = f1;
    }
  }
  const std::vector<float> importance = model->featureImportance();
  for (std::size_t i = 0; i < importance.size(); ++i) {
    std::printf("  importance %-18s %.3f\n", core::kFeatureNames[i], importance[i]);
  }
  model->save(*out);
  std::printf("%s model trained on %zu points written to %s\n", learn::toString(model->kind()),
              train.truth.size(), out->c_str());
  return 0;
}

#else

void registerClassifierLoader() {}

int runTrain(const std::vector<std::string>&) {
  throw std::runtime_error("this upd was built without libs/learn (OpenCV's ml module, "
                           "libopencv-ml-dev): it cannot train a classifier");
}

#endif

}  // namespace upd::app
