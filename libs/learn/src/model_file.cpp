// Model files of the learned classifier: an OpenCV FileStorage written atomically
// (classifier.h).
#include "classifier_impl.h"
#include "model_bytes.h"

#include "upd/io/atomic_file.h"
#include "upd/io/whole_file.h"

#include <cstdint>
#include <filesystem>
#include <ostream>
#include <stdexcept>

namespace upd::learn {

namespace {

constexpr const char* kMetaNode = "upd_point_classifier";

std::runtime_error fileError(const std::string& path, const std::string& what) {
  return std::runtime_error("classifier '" + path + "': " + what);
}

// The format extension (".yml" ...) and whether the file is gzip-compressed (".yml.gz").
std::string formatOf(const std::string& path, bool* gz = nullptr) {
  std::filesystem::path p(path);
  const bool compressed = p.extension() == ".gz";
  if (compressed) p = p.stem();
  if (gz) *gz = compressed;
  const std::string ext = p.extension().string();
  if (ext == ".yml" || ext == ".yaml" || ext == ".xml" || ext == ".json") return ext;
  throw std::invalid_argument("classifier file '" + path +
                              "': the extension must be .yml, .yaml, .xml or .json (+ .gz)");
}

void writeModel(cv::FileStorage& fs, const PointClassifier::Impl& m);

// The largest model file read, compressed or not (the shipped random trees: 5 MB of YAML).
constexpr std::uintmax_t kMaxModelBytes = std::uintmax_t{1} << 30;

// OpenCV's FileStorage format flag for the extension.
int formatFlag(const std::string& format) {
  if (format == ".xml") return cv::FileStorage::FORMAT_XML;
  if (format == ".json") return cv::FileStorage::FORMAT_JSON;
  return cv::FileStorage::FORMAT_YAML;
}

// What went wrong, in one line: OpenCV 4.6's parser errors hold their text ("(line): what") in
// func and the parser's function's name in err; its other errors their text in err.
std::string reasonOf(const cv::Exception& e) {
  const std::size_t at = e.func.rfind("): ");
  const std::size_t open = at == std::string::npos ? at : e.func.rfind('(', at);
  if (open != std::string::npos) {
    return "line " + e.func.substr(open + 1, at - open - 1) + ": " + e.func.substr(at + 3);
  }
  return e.err;
}

cv::Ptr<cv::ml::StatModel> emptyModel(ModelKind kind) {
  if (kind == ModelKind::RandomTrees) return cv::ml::RTrees::create();
  if (kind == ModelKind::Boost) return cv::ml::Boost::create();
  return cv::ml::SVM::create();
}

void writeMeta(cv::FileStorage& fs, const PointClassifier::Impl& m) {
  fs << kMetaNode << "{";
  fs << "kind" << toString(m.kind);
  fs << "radius_small_m" << m.features.radius_small_m << "radius_m" << m.features.radius_m
     << "radius_large_m" << m.features.radius_large_m << "cell_m" << m.features.cell_m
     << "min_neighbors" << m.features.min_neighbors;
  fs << "features" << "[";
  for (const char* n : core::kFeatureNames) fs << n;
  fs << "]";
  fs << "mean" << m.mean << "scale" << m.scale << "raw_sign" << m.raw_sign;
  fs << "}";
}

PointClassifier::Impl readMeta(const cv::FileNode& meta, const std::string& path) {
  if (meta.empty() || !meta.isMap()) {
    throw fileError(path, std::string("not an UPD-Nav classifier (no '") + kMetaNode + "' node)");
  }
  PointClassifier::Impl m;
  try {
    m.kind = parseModelKind(static_cast<std::string>(meta["kind"]));
  } catch (const std::invalid_argument& e) {
    throw fileError(path, e.what());
  }
  meta["radius_small_m"] >> m.features.radius_small_m;
  meta["radius_m"] >> m.features.radius_m;
  meta["radius_large_m"] >> m.features.radius_large_m;
  meta["cell_m"] >> m.features.cell_m;
  meta["min_neighbors"] >> m.features.min_neighbors;
  meta["mean"] >> m.mean;
  meta["scale"] >> m.scale;
  meta["raw_sign"] >> m.raw_sign;
  if (meta["features"].size() != static_cast<std::size_t>(core::kFeatureCount) ||
      m.mean.cols != core::kFeatureCount || m.scale.cols != core::kFeatureCount) {
    throw fileError(path, "made for other features (this upd computes " +
                              std::to_string(core::kFeatureCount) + ")");
  }
  try {
    m.features.validate();
  } catch (const std::invalid_argument& e) {
    throw fileError(path, e.what());
  }
  return m;
}

void writeModel(cv::FileStorage& fs, const PointClassifier::Impl& m) {
  writeMeta(fs, m);
  fs << "model" << "{";
  m.model->write(fs);
  fs << "}";
}

}  // namespace

void PointClassifier::save(const std::string& path) const {
  bool gz = false;
  const std::string format = formatOf(path, &gz);
  cv::FileStorage fs(format, cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  writeModel(fs, *impl_);
  const std::string text = detail::withChecksum(fs.releaseAndGetString(), format);
  const std::string bytes = gz ? detail::gzip(text) : text;
  io::writeFileAtomically(path, [&](std::ostream& out) {
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  });
}

std::shared_ptr<PointClassifier> PointClassifier::load(const std::string& path) {
  bool gz = false;
  const std::string format = formatOf(path, &gz);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw fileError(path, "no such file");
  // The bytes checked before OpenCV parses them (model_bytes.h).
  std::string text;
  try {
    text = io::readWholeFile(path, kMaxModelBytes);
    if (gz) text = detail::gunzip(text, kMaxModelBytes);
    detail::checkChecksum(text, format);
  } catch (const std::runtime_error& e) {
    throw fileError(path, e.what());
  }
  try {
    cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | formatFlag(format));
    if (!fs.isOpened()) throw fileError(path, "cannot open for reading");
    auto impl = std::make_shared<Impl>(readMeta(fs[kMetaNode], path));
    impl->model = emptyModel(impl->kind);
    impl->model->read(fs["model"]);
    if (!impl->model->isTrained()) throw fileError(path, "its 'model' node holds no trained model");
    return std::make_shared<PointClassifier>(impl);
  } catch (const cv::Exception& e) {
    throw fileError(path, "OpenCV cannot read it (" + reasonOf(e) + ")");
  }
}

void registerLoader() {
  core::setPointLabelerLoader([](const std::string& path) -> std::shared_ptr<const core::PointLabeler> {
    return PointClassifier::load(path);
  });
}

}  // namespace upd::learn
