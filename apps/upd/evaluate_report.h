// The output of `upd evaluate`: evaluation.md (Markdown tables per group, per point and per
// map cell), evaluation.json (the same numbers with thinned ROC curves) and one ROC plot per
// group and d_m (roc_<group>_d<d_m>.png). Every file is written atomically.
#pragma once

#include "evaluate_scores.h"

#include <string>
#include <vector>

namespace upd::app {

struct GroupReport {
  std::string group;
  std::size_t clouds = 0, points = 0, cells = 0;
  std::vector<std::string> clouds_scored;
  std::vector<MethodResult> per_point, per_cell;
};

struct EvaluationReport {
  std::string command;
  EvalSettings settings;
  std::string classifier_path;  ///< "" when none
  std::vector<GroupReport> groups;
  std::vector<std::string> notes;
};

/// Writes evaluation.md, evaluation.json and the ROC plots into dir (made when missing).
void writeEvaluation(const EvaluationReport& report, const std::string& dir);

}  // namespace upd::app
