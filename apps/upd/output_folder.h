// The folder a command writes its outputs into, created with its missing parents; when the
// command fails before keep(), the folders it created are removed again if they are still empty,
// so an error leaves nothing behind, not even an empty folder.
#pragma once

#include <filesystem>
#include <vector>

namespace upd::app {

class OutputFolder {
 public:
  explicit OutputFolder(const std::filesystem::path& dir);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  /// The outputs are written: the folder stays whatever happens next.
  void keep() { created_.clear(); }

 private:
  std::vector<std::filesystem::path> created_;  ///< innermost first
};

}  // namespace upd::app
