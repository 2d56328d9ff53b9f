// The learned classifier: OpenCV ml models over the point features (classifier.h).
#include "upd/learn/classifier.h"

#include "classifier_impl.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

namespace upd::learn {

using core::kFeatureCount;

cv::Mat PointClassifier::Impl::standardized(const std::vector<float>& f) const {
  const int rows = static_cast<int>(f.size() / kFeatureCount);
  const cv::Mat m(rows, kFeatureCount, CV_32F, const_cast<float*>(f.data()));
  cv::Mat out(rows, kFeatureCount, CV_32F);
  for (int r = 0; r < rows; ++r) cv::multiply(m.row(r) - mean, scale, out.row(r));
  return out;
}

namespace {

const char* const kNames[] = {"rtrees", "boost", "svm"};

void requireRows(const std::vector<float>& f, std::size_t rows, const char* what) {
  if (f.size() % kFeatureCount || (rows && f.size() / kFeatureCount != rows)) {
    throw std::invalid_argument(std::string(what) + ": " + std::to_string(f.size()) +
                                " feature values is not " + std::to_string(kFeatureCount) +
                                " per point" + (rows ? " for " + std::to_string(rows) + " points" : ""));
  }
}

// At most per_class rows of each class, drawn with the seed; returns the row indices.
std::vector<std::size_t> balancedSample(const std::vector<core::Label>& truth, int per_class,
                                        int seed) {
  std::vector<std::size_t> pos, neg;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (truth[i] == core::Label::NonTraversable) pos.push_back(i);
    if (truth[i] == core::Label::Traversable) neg.push_back(i);
  }
  if (pos.empty() || neg.empty()) {
    throw std::invalid_argument("training data needs both traversable and non-traversable points (" +
                                std::to_string(neg.size()) + " and " + std::to_string(pos.size()) + ")");
  }
  std::mt19937 rng(static_cast<std::uint32_t>(seed));
  std::vector<std::size_t> out;
  for (auto* v : {&pos, &neg}) {
    std::shuffle(v->begin(), v->end(), rng);
    v->resize(std::min<std::size_t>(v->size(), static_cast<std::size_t>(per_class)));
    out.insert(out.end(), v->begin(), v->end());
  }
  return out;
}

cv::Ptr<cv::ml::StatModel> makeModel(const TrainParams& p) {
  if (p.kind == ModelKind::RandomTrees) {
    auto m = cv::ml::RTrees::create();
    m->setMaxDepth(p.max_depth);
    m->setMinSampleCount(5);
    m->setCalculateVarImportance(true);
    m->setTermCriteria(cv::TermCriteria(cv::TermCriteria::MAX_ITER, p.trees, 0));
    return m;
  }
  if (p.kind == ModelKind::Boost) {
    auto m = cv::ml::Boost::create();
    m->setBoostType(cv::ml::Boost::GENTLE);
    m->setWeakCount(p.trees);
    m->setMaxDepth(3);
    return m;
  }
  auto m = cv::ml::SVM::create();
  m->setType(cv::ml::SVM::C_SVC);
  m->setKernel(cv::ml::SVM::RBF);
  m->setC(10);
  m->setGamma(1.0 / kFeatureCount);
  m->setTermCriteria(cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, 2000, 1e-3));
  return m;
}

// Raw decision values (boosting, SVM) or the vote share of class 1 (random trees).
std::vector<float> rawScores(const PointClassifier::Impl& impl, const cv::Mat& x) {
  std::vector<float> out(static_cast<std::size_t>(x.rows));
  if (x.rows == 0) return out;
  if (impl.kind == ModelKind::RandomTrees) {
    cv::Mat votes;
    impl.model.dynamicCast<cv::ml::RTrees>()->getVotes(x, votes, 0);
    int col = -1, total = 0;
    for (int c = 0; c < votes.cols; ++c) {
      if (votes.at<int>(0, c) == 1) col = c;
    }
    for (int r = 0; r < x.rows; ++r) {
      total = 0;
      for (int c = 0; c < votes.cols; ++c) total += votes.at<int>(r + 1, c);
      out[r] = col < 0 || total == 0 ? 0.f : float(votes.at<int>(r + 1, col)) / float(total);
    }
    return out;
  }
  cv::Mat res;  // boosting returns its class unless asked for the sum of its weak learners
  impl.model->predict(x, res, cv::ml::StatModel::RAW_OUTPUT | cv::ml::DTrees::PREDICT_SUM);
  for (int r = 0; r < x.rows; ++r) out[r] = res.at<float>(r, 0);
  return out;
}

}  // namespace

const char* toString(ModelKind kind) { return kNames[static_cast<int>(kind)]; }

ModelKind parseModelKind(const std::string& name) {
  for (int i = 0; i < 3; ++i) {
    if (name == kNames[i]) return static_cast<ModelKind>(i);
  }
  throw std::invalid_argument("model '" + name + "': expected rtrees, boost or svm");
}

void TrainParams::validate() const {
  core::requireParam(max_samples >= 10, "TrainParams", "max_samples", max_samples, "must be >= 10");
  core::requireParam(trees >= 1 && trees <= 2000, "TrainParams", "trees", trees, "must be in 1 .. 2000");
  core::requireParam(max_depth >= 1 && max_depth <= 30, "TrainParams", "max_depth", max_depth,
                     "must be in 1 .. 30");
}

std::shared_ptr<PointClassifier> PointClassifier::train(const std::vector<float>& features,
                                                        const std::vector<core::Label>& truth,
                                                        const core::FeatureParams& feature_params,
                                                        const TrainParams& params) {
  params.validate();
  feature_params.validate();
  requireRows(features, truth.size(), "PointClassifier::train");
  const int cap = params.kind == ModelKind::Svm ? std::min(params.max_samples, 10000) : params.max_samples;
  const std::vector<std::size_t> rows = balancedSample(truth, cap / 2, params.seed);
  cv::Mat x(static_cast<int>(rows.size()), kFeatureCount, CV_32F), y(x.rows, 1, CV_32S);
  for (int r = 0; r < x.rows; ++r) {
    std::copy_n(&features[rows[r] * kFeatureCount], kFeatureCount, x.ptr<float>(r));
    y.at<int>(r, 0) = truth[rows[r]] == core::Label::NonTraversable ? 1 : 0;
  }
  auto impl = std::make_shared<Impl>();
  impl->kind = params.kind;
  impl->features = feature_params;
  cv::Mat sd;
  cv::reduce(x, impl->mean, 0, cv::REDUCE_AVG);
  cv::Mat centred = x - cv::repeat(impl->mean, x.rows, 1);
  cv::reduce(centred.mul(centred), sd, 0, cv::REDUCE_AVG);
  cv::sqrt(sd, sd);
  impl->scale = 1.0 / cv::max(sd, 1e-6);
  impl->model = makeModel(params);
  impl->model->train(cv::ml::TrainData::create(impl->standardized(std::vector<float>(x.begin<float>(), x.end<float>())),
                                               cv::ml::ROW_SAMPLE, y));
  if (params.kind != ModelKind::RandomTrees) {  // which sign of the raw output is class 1
    const std::vector<float> raw = rawScores(*impl, impl->standardized(std::vector<float>(x.begin<float>(), x.end<float>())));
    double m1 = 0, m0 = 0;
    for (int r = 0; r < x.rows; ++r) (y.at<int>(r, 0) ? m1 : m0) += raw[r];
    impl->raw_sign = m1 >= m0 ? 1.f : -1.f;
  }
  return std::make_shared<PointClassifier>(impl);
}

std::vector<float> PointClassifier::probabilityOfFeatures(const std::vector<float>& features) const {
  requireRows(features, 0, "PointClassifier");
  std::vector<float> p = rawScores(*impl_, impl_->standardized(features));
  if (impl_->kind == ModelKind::RandomTrees) return p;
  // Boosting sums weak outputs in [-1, 1]: 4 / count maps a unanimous vote to p = 0.98.
  const float gain = impl_->kind == ModelKind::Boost
                         ? 4.f / impl_->model.dynamicCast<cv::ml::Boost>()->getWeakCount()
                         : 1.f;
  for (float& v : p) v = 1.f / (1.f + std::exp(-gain * impl_->raw_sign * v));
  return p;
}

const core::FeatureParams& PointClassifier::featureParams() const { return impl_->features; }
ModelKind PointClassifier::kind() const { return impl_->kind; }

std::vector<float> PointClassifier::featureImportance() const {
  if (impl_->kind != ModelKind::RandomTrees) return {};
  const cv::Mat imp = impl_->model.dynamicCast<cv::ml::RTrees>()->getVarImportance();
  std::vector<float> out(imp.begin<float>(), imp.end<float>());
  const float sum = std::accumulate(out.begin(), out.end(), 0.f);
  if (sum > 0) {
    for (float& v : out) v /= sum;
  }
  return out;
}

}  // namespace upd::learn
