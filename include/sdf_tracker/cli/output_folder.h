#pragma once

#include <string>
#include <vector>

namespace sdf_tracker::tools {

/// Where a run's results go. Files are written into a staging folder inside `directory` and moved
/// into place by commit(), the summary last, after the previous run's results are removed: a run
/// that fails or is killed never leaves half-written files, and never a summary that describes
/// other files than those beside it. Staging folders of killed runs are removed at the next start.
class OutputFolder {
 public:
  /// `results` names every file a run may write (so a previous run's are known). Throws
  /// std::invalid_argument for an empty path, std::runtime_error when it cannot be created.
  OutputFolder(const std::string& directory, std::vector<std::string> results);
  ~OutputFolder();  ///< removes the staging folder unless committed
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  /// Where to write result `name` now (inside the staging folder).
  std::string path(const std::string& name) const;
  /// Replaces the previous run's results with this run's; `last` (the summaries) move last.
  void commit(const std::vector<std::string>& last);

 private:
  std::string directory_;
  std::string staging_;
  std::vector<std::string> results_;
  bool committed_ = false;
};

}  // namespace sdf_tracker::tools
