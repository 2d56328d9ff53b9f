// Class maps: class id -> traversability, read from a small text file.
#include "upd/io/class_map.h"

#include "upd/io/kitti_bin.h"

#include "io_detail.h"

#include <fstream>
#include <sstream>

namespace upd::io {

namespace {

core::Label parseClass(const std::string& word, const std::string& where) {
  if (word == "traversable") return core::Label::Traversable;
  if (word == "non-traversable") return core::Label::NonTraversable;
  if (word == "ignore") return core::Label::Unknown;
  throw std::runtime_error(where + ": class '" + word +
                           "' is not traversable, non-traversable or ignore");
}

std::uint16_t parseId(const std::string& word, const std::string& where) {
  std::size_t used = 0;
  long id = -1;
  try {
    id = std::stol(word, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != word.size() || id < 0 || id > 65535) {
    throw std::runtime_error(where + ": class id '" + word + "' is not an integer 0 .. 65535");
  }
  return static_cast<std::uint16_t>(id);
}

}  // namespace

ClassMap readClassMap(const std::string& path) {
  detail::requireReadableFile(path);
  std::ifstream in(path);
  if (!in) throw detail::fileError(path, "cannot open for reading");
  ClassMap map;
  map.path = path;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream words(line);
    std::string id_text, cls, name, word;
    if (!(words >> id_text)) continue;
    const std::string where = path + ":" + std::to_string(n);
    if (!(words >> cls)) throw std::runtime_error(where + ": expected 'ID CLASS [NAME]'");
    while (words >> word) name += (name.empty() ? "" : " ") + word;
    const std::uint16_t id = parseId(id_text, where);
    if (map.classes.count(id)) {
      throw std::runtime_error(where + ": class id " + id_text + " listed twice");
    }
    map.classes[id] = parseClass(cls, where);
    map.names[id] = name;
  }
  if (map.classes.empty()) throw detail::fileError(path, "no class listed (a class map?)");
  return map;
}

std::vector<core::Label> truthFromLabels(const std::vector<std::uint32_t>& labels,
                                         const ClassMap& map, const std::string& labels_path) {
  std::vector<core::Label> truth(labels.size());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const std::uint16_t id = semanticClassOf(labels[i]);
    const auto it = map.classes.find(id);
    if (it == map.classes.end()) {
      throw std::runtime_error(labels_path + ": point " + std::to_string(i) + " has class id " +
                               std::to_string(id) + ", which class map " + map.path +
                               " does not list");
    }
    truth[i] = it->second;
  }
  return truth;
}

}  // namespace upd::io
