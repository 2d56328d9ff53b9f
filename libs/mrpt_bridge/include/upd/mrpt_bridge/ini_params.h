// Loading the library's parameter structs from MRPT ini files, strictly.
//
// Each options struct is read from the [Section] named after it (MRPT's convention), through the
// struct's visit(), so the key names, units and defaults are written once, in the struct. A
// missing file, an unknown section or key, a key given twice, or a value that does not parse
// stops with one line naming the file, section, key and value; a value that parses but breaks a
// rule is reported by the struct's validate(), prefixed with the file.
#pragma once

#include "upd/core/params.h"

#include <Eigen/Core>

#include <cstddef>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace mrpt::config {
class CConfigFileBase;
}

namespace upd {

namespace core {
struct PipelineParams;
}  // namespace core

namespace mrpt_bridge {

class IniReader {
 public:
  /// Opens path; throws std::runtime_error naming it when it is missing or unreadable.
  explicit IniReader(const std::string& path);
  ~IniReader();
  IniReader(const IniReader&) = delete;
  IniReader& operator=(const IniReader&) = delete;

  /// Fills params from [section] when present (keys absent keep their defaults) and validates.
  template <class P>
  void read(const std::string& section, P& params);

  /// Throws when the file holds a section or key nobody read (a typo must not pass silently).
  void checkAllKeysKnown() const;
  const std::string& path() const { return path_; }

  // Used by read(); public so the visitor can reach them.
  std::string rawValue(const std::string& section, const std::string& key) const;
  bool hasKey(const std::string& section, const std::string& key) const;
  [[noreturn]] void fail(const std::string& section, const std::string& key,
                         const std::string& value, const std::string& why) const;
  void markKnown(const std::string& section, const std::string& key);

 private:
  std::string path_;
  std::unique_ptr<mrpt::config::CConfigFileBase> cfg_;
  std::map<std::string, std::set<std::string>> known_;
};

namespace detail {
double parseDouble(const IniReader& r, const std::string& s, const std::string& k,
                   const std::string& v);
int parseInt(const IniReader& r, const std::string& s, const std::string& k,
             const std::string& v);
bool parseBool(const IniReader& r, const std::string& s, const std::string& k,
               const std::string& v);
Eigen::Vector3f parseVector3(const IniReader& r, const std::string& s, const std::string& k,
                             const std::string& v);
/// The index in names of v: a name (any case) or, as configs written before the names hold,
/// the number of one (numbers[i]). Fails naming the valid names otherwise.
std::size_t parseChoice(const IniReader& r, const std::string& s, const std::string& k,
                        const std::string& v, const std::vector<std::string>& names,
                        const std::vector<int>& numbers);
void rethrowWithFile(const IniReader& r, const std::string& section);

struct IniVisitor {
  IniReader& reader;
  const std::string& section;
  template <class T>
  void operator()(const char* key, T& value, const char* /*doc*/) {
    reader.markKnown(section, key);
    if (!reader.hasKey(section, key)) return;
    const std::string v = reader.rawValue(section, key);
    if constexpr (std::is_same_v<T, double>) {
      value = parseDouble(reader, section, key, v);
    } else if constexpr (std::is_same_v<T, int>) {
      value = parseInt(reader, section, key, v);
    } else if constexpr (std::is_same_v<T, bool>) {
      value = parseBool(reader, section, key, v);
    } else {
      value = parseVector3(reader, section, key, v);
    }
  }
  void angleDeg(const char* key, double& radians, const char* doc) {
    double deg = radians * 180.0 / 3.14159265358979323846;
    (*this)(key, deg, doc);
    radians = deg * 3.14159265358979323846 / 180.0;
  }
  template <class E, std::size_t N>
  void choice(const char* key, E& value, const core::EnumName<E> (&names)[N], const char* /*doc*/) {
    reader.markKnown(section, key);
    if (!reader.hasKey(section, key)) return;
    std::vector<std::string> texts;
    std::vector<int> numbers;
    for (const auto& n : names) {
      texts.emplace_back(n.name);
      numbers.push_back(static_cast<int>(n.value));
    }
    value = names[parseChoice(reader, section, key, reader.rawValue(section, key), texts, numbers)]
                .value;
  }
};
}  // namespace detail

template <class P>
void IniReader::read(const std::string& section, P& params) {
  detail::IniVisitor v{*this, section};
  params.visit(v);
  try {
    params.validate();
  } catch (...) {
    detail::rethrowWithFile(*this, section);
  }
}

/// `[ClassifyParams] classifier = FILE`, the learned classifier (upd/core/point_labeler.h; a
/// relative FILE is relative to the ini file), loaded into pipeline.labeler when present.
/// Marks the key known; throws naming the file and key when the model cannot be loaded.
void readClassifier(IniReader& ini, core::PipelineParams& pipeline);

/// Reads [PipelineParams] (key `up`), [PreprocessParams], [NormalParams], [UpdParams] and
/// [ClassifyParams] into params, then checks that the file holds nothing else.
void loadPipelineParams(const std::string& ini_path, core::PipelineParams& params);

}  // namespace mrpt_bridge
}  // namespace upd
