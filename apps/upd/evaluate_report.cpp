// evaluation.md, evaluation.json and the ROC plots of `upd evaluate` (evaluate_report.h).
#include "evaluate_report.h"

#include "upd/io/atomic_file.h"
#include "upd/io/json_io.h"
#include "upd/nav/figure_roc.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace upd::app {

namespace {

std::string num(double v, const char* f = "%.3f") {
  if (std::isnan(v)) return "–";
  char buf[32];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string radiusText(double r) { return r > 0 ? num(r, "%.2g") : ""; }

std::string slug(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (std::isalnum(static_cast<unsigned char>(c))) out += char(std::tolower(c));
    else if (!out.empty() && out.back() != '-') out += '-';
  }
  while (!out.empty() && out.back() == '-') out.pop_back();
  return out;
}

std::string rocFile(const GroupReport& g, double r) {
  return "roc_" + slug(g.group) + "_d" + num(r, "%.2g") + ".png";
}

void markdownTable(std::ostream& md, const std::vector<MethodResult>& results) {
  md << "| detector | d_m [m] | rule | precision | recall | F1 | best F1 | AUC |\n"
        "|---|---|---|---|---|---|---|---|\n";
  for (const MethodResult& r : results) {
    md << "| " << r.name << " | " << radiusText(r.radius_m) << " | " << r.rule << " | "
       << num(r.counts.precision()) << " | " << num(r.counts.recall()) << " | "
       << num(r.counts.f1()) << " | " << num(r.roc.best_f1) << " | " << num(r.roc.auc) << " |\n";
  }
}

void markdownGroup(std::ostream& md, const GroupReport& g, const EvaluationReport& rep) {
  md << "## " << g.group << "\n\n"
     << g.clouds << " clouds, " << g.points << " scored points, " << g.cells << " map cells of "
     << rep.settings.cell_m << " m. Clouds: ";
  for (std::size_t i = 0; i < g.clouds_scored.size(); ++i) {
    md << (i ? ", " : "") << g.clouds_scored[i];
  }
  md << ".\n\n### Per point\n\n";
  markdownTable(md, g.per_point);
  md << "\n### Per map cell (" << rep.settings.cell_m
     << " m: an obstacle if any of its points is, scored by its highest score)\n\n";
  markdownTable(md, g.per_cell);
  md << "\n";
  for (double r : rep.settings.radii_m) {
    md << "![ROC, " << g.group << ", d_m = " << r << " m](" << rocFile(g, r) << ")\n";
  }
  md << "\n";
}

nlohmann::json resultJson(const MethodResult& r) {
  const core::RocCurve roc = r.roc.thinned(60);
  return {{"detector", r.name},       {"d_m", r.radius_m},
          {"rule", r.rule},           {"tp", r.counts.tp},
          {"fp", r.counts.fp},        {"tn", r.counts.tn},
          {"fn", r.counts.fn},        {"precision", r.counts.precision()},
          {"recall", r.counts.recall()}, {"f1", r.counts.f1()},
          {"best_f1", r.roc.best_f1}, {"best_threshold", r.roc.best_threshold},
          {"auc", r.roc.auc},         {"roc", {{"fpr", roc.fpr}, {"tpr", roc.tpr}}}};
}

nlohmann::json reportJson(const EvaluationReport& rep) {
  nlohmann::json j = {{"command", rep.command},
                      {"d_m", rep.settings.radii_m},
                      {"cell_m", rep.settings.cell_m},
                      {"classifier", rep.classifier_path},
                      {"notes", rep.notes},
                      {"groups", nlohmann::json::array()}};
  for (const GroupReport& g : rep.groups) {
    nlohmann::json jg = {{"group", g.group},   {"clouds", g.clouds_scored},
                         {"points", g.points}, {"cells", g.cells},
                         {"per_point", nlohmann::json::array()},
                         {"per_cell", nlohmann::json::array()}};
    for (const auto& r : g.per_point) jg["per_point"].push_back(resultJson(r));
    for (const auto& r : g.per_cell) jg["per_cell"].push_back(resultJson(r));
    j["groups"].push_back(jg);
  }
  return j;
}

void plotGroup(const GroupReport& g, const EvaluationReport& rep, const std::string& dir) {
  for (double d : rep.settings.radii_m) {
    std::vector<nav::RocSeries> series;
    for (const MethodResult& r : g.per_point) {
      if (r.radius_m != d && r.radius_m != 0) continue;
      if (std::isnan(r.roc.auc)) continue;
      const core::RocCurve thin = r.roc.thinned(400);
      series.push_back({r.name, thin.fpr, thin.tpr, r.roc.auc});
    }
    if (series.empty()) continue;
    nav::drawRocCurves(series, g.group + ", per point, d_m = " + num(d, "%.2g") + " m",
                       (std::filesystem::path(dir) / rocFile(g, d)).string());
  }
}

}  // namespace

void writeEvaluation(const EvaluationReport& rep, const std::string& dir) {
  std::filesystem::create_directories(dir);
  std::ostringstream md;
  md << "# Traversability evaluation\n\n`" << rep.command << "`\n\n"
     << "The positive class is non-traversable. Precision, recall and F1 are those of each "
        "detector's rule (its fixed threshold); best F1 is the highest F1 over all thresholds "
        "of its score (chosen on the data scored: an upper bound, not a result); AUC is the "
        "area under the ROC curve of its score. d_m is the neighbourhood radius.\n\n"
     << "Classifier: " << (rep.classifier_path.empty() ? "none" : "`" + rep.classifier_path + "`")
     << "\n\n";
  for (const GroupReport& g : rep.groups) {
    markdownGroup(md, g, rep);
    plotGroup(g, rep, dir);
  }
  if (!rep.notes.empty()) {
    md << "## Notes\n\n";
    for (const auto& n : rep.notes) md << "- " << n << "\n";
  }
  const std::string text = md.str();
  io::writeFileAtomically((std::filesystem::path(dir) / "evaluation.md").string(),
                          [&](std::ostream& out) { out << text; });
  io::writeJsonAtomically((std::filesystem::path(dir) / "evaluation.json").string(), reportJson(rep));
}

}  // namespace upd::app
