// Calibration YAMLs checked line by line, then opened by OpenCV's parser (yaml_text.h).
#include "yaml_text.h"

#include "upd/io/whole_file.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <stdexcept>

namespace upd::mrpt_bridge {

namespace {

bool plainChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '+' ||
         c == '-' || c == '/';
}

// s[at, ...) from the first character that is not a blank.
std::size_t skipBlanks(const std::string& s, std::size_t at) {
  while (at < s.size() && (s[at] == ' ' || s[at] == '\t')) ++at;
  return at;
}

// Whether s[at, ...) is a run of list items (plain tokens, commas, blanks), then the list's end
// (closed set) and nothing after it but blanks.
bool listItems(const std::string& s, std::size_t at, bool& closed) {
  closed = false;
  for (; at < s.size(); ++at) {
    const char c = s[at];
    if (c == ']') {
      closed = true;
      return skipBlanks(s, at + 1) == s.size();
    }
    if (!plainChar(c) && c != ',' && c != ' ' && c != '\t') return false;
  }
  return true;
}

// Whether v (what follows "key:") is a value of the subset: nothing (a block follows), a tag,
// a list of plain items (open: it goes on over the next lines), a quoted string, a plain
// scalar.
bool valueOfSubset(const std::string& v, bool& opens_block, bool& open_list) {
  opens_block = open_list = false;
  const std::size_t at = skipBlanks(v, 0);
  if (at == v.size()) return opens_block = true;
  if (at == 0) return false;  // ("key:value")
  const std::string x = v.substr(at);
  if (x == "!!opencv-matrix") return opens_block = true;
  if (x[0] == '[') {
    bool closed = false;
    if (!listItems(x, 1, closed)) return false;
    open_list = !closed;
    return true;
  }
  if (x[0] == '"' || x[0] == '\'') {
    const std::size_t end = x.find(x[0], 1);
    return end != std::string::npos && x.find('\\') == std::string::npos &&
           skipBlanks(x, end + 1) == x.size();
  }
  return std::all_of(x.begin(), x.end(), [](char c) { return plainChar(c) || c == ' '; });
}

// The line without its comment (from a '#' at its start or after a blank, outside quotes) and
// its trailing blanks and carriage return.
std::string withoutComment(const std::string& l) {
  char quote = 0;
  std::size_t end = l.size();
  for (std::size_t i = 0; i < l.size(); ++i) {
    const char c = l[i];
    if (quote) {
      quote = c == quote ? 0 : quote;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#' && (i == 0 || l[i - 1] == ' ' || l[i - 1] == '\t')) {
      end = i;
      break;
    }
  }
  while (end > 0 && (l[end - 1] == ' ' || l[end - 1] == '\t' || l[end - 1] == '\r')) --end;
  return l.substr(0, end);
}

class SubsetCheck {
 public:
  SubsetCheck(const std::string& file, const std::string& what) : file_(file), what_(what) {}

  void line(const std::string& raw, std::size_t number) {
    const std::string l = withoutComment(raw);
    if (ended_ && !l.empty()) fail(number, "text after '...', the end of the document");
    if (l.empty()) return;
    if (open_list_) {
      bool closed = false;
      if (!listItems(l, 0, closed)) bad(number, l);
      open_list_ = !closed;
      return;
    }
    if (number == 1 && l.rfind("%YAML", 0) == 0) return;
    if (l == "---" && !any_key_) return;
    if (l == "...") {
      ended_ = true;
      return;
    }
    const std::size_t indent = skipBlanks(l, 0);
    std::size_t colon = indent;
    while (colon < l.size() && (plainChar(l[colon]) && l[colon] != '.' && l[colon] != '/')) {
      ++colon;
    }
    if (colon == indent || colon == l.size() || l[colon] != ':' ||
        !std::isalpha(static_cast<unsigned char>(l[indent]))) {
      bad(number, l);
    }
    bool opens_block = false;
    if (!valueOfSubset(l.substr(colon + 1), opens_block, open_list_)) bad(number, l);
    if (indent == 0) {
      in_block_ = opens_block;
      block_indent_ = 0;
    } else {
      // (A key indented under a key that opened a block, all of its keys alike; none opens
      // another.)
      if (!in_block_ || opens_block) bad(number, l);
      if (block_indent_ == 0) block_indent_ = indent;
      if (indent != block_indent_) bad(number, l);
    }
    any_key_ = true;
  }
  void end(std::size_t number) const {
    if (open_list_) fail(number, "a list '[' is not closed");
  }

 private:
  [[noreturn]] void fail(std::size_t number, const std::string& why) const {
    throw std::runtime_error(what_ + " " + file_ + ": line " + std::to_string(number) + ": " +
                             why);
  }
  [[noreturn]] void bad(std::size_t number, const std::string& l) const {
    fail(number, "'" + l.substr(0, 40) + (l.size() > 40 ? "...'" : "'") +
                     " is not a line of a calibration (key: value, key: [numbers], or such a "
                     "key indented under a key of its own)");
  }

  const std::string& file_;
  const std::string& what_;
  bool open_list_ = false, in_block_ = false, ended_ = false, any_key_ = false;
  std::size_t block_indent_ = 0;
};

void checkText(const std::string& yaml, const std::string& file, const std::string& what) {
  std::size_t number = 1;
  for (const char ch : yaml) {
    const auto b = static_cast<unsigned char>(ch);
    const bool control = b < 0x20 && b != '\t' && b != '\n' && b != '\r';
    if (control || b >= 0x80) {
      throw std::runtime_error(
          what + " " + file + ": line " + std::to_string(number) + ": byte " +
          std::to_string(b) +
          (control ? ": a control character, not text" : ": not ASCII (a calibration is ASCII)"));
    }
    number += b == '\n' ? 1 : 0;
  }
  SubsetCheck check(file, what);
  number = 1;
  for (std::size_t at = 0; at < yaml.size(); ++number) {
    const std::size_t end = std::min(yaml.find('\n', at), yaml.size());
    check.line(yaml.substr(at, end - at), number);
    at = end + 1;
  }
  check.end(number);
}

}  // namespace

cv::FileStorage openCheckedYaml(const std::string& file, const std::string& what) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error(what + " " + file + ": " + why);
  };
  // (A calibration is a few kB: 16 MB is no calibration.)
  std::string yaml;
  try {
    yaml = io::readWholeFile(file, std::uintmax_t{1} << 24);
  } catch (const std::runtime_error& e) {
    throw fail(e.what());
  }
  checkText(yaml, file, what);
  if (yaml.rfind("%YAML", 0) != 0) yaml = "%YAML:1.0\n---\n" + yaml;
  try {
    cv::FileStorage fs(yaml, cv::FileStorage::READ | cv::FileStorage::MEMORY |
                                 cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened()) throw fail("unreadable");
    // (Empty, or only comments and directives: said so, not as the first field it lacks.)
    const cv::FileNode root = fs.root();
    if (root.empty() || (root.isMap() && root.size() == 0)) throw fail("empty: no fields");
    return fs;
  } catch (const cv::Exception& e) {
    throw fail("not valid YAML (" + e.err + ")");
  } catch (const std::length_error&) {  // (OpenCV's parser on a key with no name)
    throw fail("not valid YAML");
  }
}

}  // namespace upd::mrpt_bridge
