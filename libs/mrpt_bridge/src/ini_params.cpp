#include "upd/mrpt_bridge/ini_params.h"

#include "upd/core/pipeline.h"
#include "upd/mrpt_bridge/robot_config.h"

#include <mrpt/config/CConfigFile.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace upd::mrpt_bridge {

namespace {
std::string trim(std::string s) {
  const auto not_space = [](unsigned char c) { return !std::isspace(c); };
  s.erase(s.begin(), std::find_if(s.begin(), s.end(), not_space));
  s.erase(std::find_if(s.rbegin(), s.rend(), not_space).base(), s.end());
  return s;
}

// MRPT keeps the last of two values of one key (also across two [Section] blocks of the same
// name) without a word: a key given twice is an error naming both lines.
void requireNoDuplicateKeys(const std::string& path) {
  std::ifstream in(path);
  std::map<std::string, std::size_t> first_line;  // "section\nkey" -> line
  std::string line, section;
  for (std::size_t n = 1; std::getline(in, line); ++n) {
    line = trim(line);
    if (line.empty() || line[0] == ';' || line[0] == '#' || line.rfind("//", 0) == 0) continue;
    if (line[0] == '[') {
      section = trim(line.substr(1, line.find(']') - 1));
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = trim(line.substr(0, eq));
    const auto [it, fresh] = first_line.emplace(section + "\n" + key, n);
    if (!fresh) {
      throw std::invalid_argument("config file " + path + ": [" + section + "] " + key +
                                  " is given twice (lines " + std::to_string(it->second) +
                                  " and " + std::to_string(n) + ")");
    }
  }
}
}  // namespace

IniReader::IniReader(const std::string& path) : path_(path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw std::runtime_error("config file " + path + ": not found");
  }
  if (!std::ifstream(path).good()) throw std::runtime_error("config file " + path + ": unreadable");
  requireNoDuplicateKeys(path);
  auto cfg = std::make_unique<mrpt::config::CConfigFile>(path);
  cfg->discardSavingChanges();  // never rewrite the user's file
  cfg_ = std::move(cfg);
}

IniReader::~IniReader() = default;

bool IniReader::hasKey(const std::string& section, const std::string& key) const {
  return cfg_->keyExists(section, key);
}

std::string IniReader::rawValue(const std::string& section, const std::string& key) const {
  std::string v = cfg_->read_string(section, key, "");
  // MRPT keeps inline comments ("0.5 // metres"): drop them.
  for (const char* c : {"//", "#", ";"}) {
    const auto pos = v.find(c);
    if (pos != std::string::npos) v.erase(pos);
  }
  return trim(v);
}

void IniReader::fail(const std::string& section, const std::string& key, const std::string& value,
                     const std::string& why) const {
  throw std::invalid_argument("config file " + path_ + ": [" + section + "] " + key + " = '" +
                              value + "': " + why);
}

void IniReader::markKnown(const std::string& section, const std::string& key) {
  known_[section].insert(key);
}

void IniReader::checkAllKeysKnown() const {
  std::vector<std::string> sections;
  cfg_->getAllSections(sections);
  for (const auto& s : sections) {
    if (s.empty()) continue;
    const auto it = known_.find(s);
    if (it == known_.end()) {
      std::string valid;
      for (const auto& [name, keys] : known_) valid += (valid.empty() ? "" : ", ") + name;
      throw std::invalid_argument("config file " + path_ + ": unknown section [" + s +
                                  "] (known: " + valid + ")");
    }
    std::vector<std::string> keys;
    cfg_->getAllKeys(s, keys);
    for (const auto& k : keys) {
      if (!it->second.count(k)) {
        throw std::invalid_argument("config file " + path_ + ": [" + s + "] unknown key '" + k +
                                    "'");
      }
    }
  }
}

namespace detail {

double parseDouble(const IniReader& r, const std::string& s, const std::string& k,
                   const std::string& v) {
  try {
    std::size_t used = 0;
    const double d = std::stod(v, &used);
    if (used == v.size()) return d;
  } catch (const std::exception&) {
  }
  r.fail(s, k, v, "not a number");
}

int parseInt(const IniReader& r, const std::string& s, const std::string& k,
             const std::string& v) {
  try {
    std::size_t used = 0;
    const int i = std::stoi(v, &used);
    if (used == v.size()) return i;
  } catch (const std::exception&) {
  }
  r.fail(s, k, v, "not an integer");
}

bool parseBool(const IniReader& r, const std::string& s, const std::string& k,
               const std::string& v) {
  std::string l = v;
  std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return std::tolower(c); });
  if (l == "true" || l == "1" || l == "yes" || l == "on") return true;
  if (l == "false" || l == "0" || l == "no" || l == "off") return false;
  r.fail(s, k, v, "not a boolean (true/false)");
}

Eigen::Vector3f parseVector3(const IniReader& r, const std::string& s, const std::string& k,
                             const std::string& v) {
  std::string t = v;
  std::replace(t.begin(), t.end(), ',', ' ');
  std::istringstream is(t);
  Eigen::Vector3f out;
  std::string extra;
  if (!(is >> out.x() >> out.y() >> out.z()) || (is >> extra) || !out.allFinite()) {
    r.fail(s, k, v, "not three numbers x,y,z");
  }
  return out;
}

std::size_t parseChoice(const IniReader& r, const std::string& s, const std::string& k,
                        const std::string& v, const std::vector<std::string>& names,
                        const std::vector<int>& numbers) {
  std::string l = v;
  std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return std::tolower(c); });
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (l == names[i]) return i;
  }
  int number = 0;
  const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), number);
  if (ec == std::errc() && end == v.data() + v.size()) {
    for (std::size_t i = 0; i < numbers.size(); ++i) {
      if (number == numbers[i]) return i;
    }
  }
  std::string valid, old;
  for (std::size_t i = 0; i < names.size(); ++i) {
    valid += (i ? ", " : "") + names[i];
    old += (i ? ", " : "") + std::to_string(numbers[i]);
  }
  r.fail(s, k, v, "not one of " + valid + " (or their old numbers " + old + ")");
}

void rethrowWithFile(const IniReader& r, const std::string& section) {
  try {
    throw;
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("config file " + r.path() + ": [" + section + "] " + e.what());
  }
}

}  // namespace detail

void loadPipelineParams(const std::string& ini_path, core::PipelineParams& params) {
  IniReader ini(ini_path);
  RobotConfigParts parts;
  parts.pipeline = &params;
  readRobotConfig(ini, parts);
  ini.checkAllKeysKnown();
  try {
    params.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("config file " + ini_path + ": " + e.what());
  }
}

void readClassifier(IniReader& ini, core::PipelineParams& pipeline) {
  const char* const section = "ClassifyParams";
  const char* const key = "classifier";
  ini.markKnown(section, key);
  if (!ini.hasKey(section, key)) return;
  std::filesystem::path file = trim(ini.rawValue(section, key));
  if (file.empty()) return;
  if (file.is_relative()) file = std::filesystem::path(ini.path()).parent_path() / file;
  try {
    pipeline.labeler = core::loadPointLabeler(file.lexically_normal().string());
  } catch (const std::exception& e) {
    throw std::runtime_error("config file " + ini.path() + ": [ClassifyParams] classifier: " +
                             e.what());
  }
}

}  // namespace upd::mrpt_bridge
