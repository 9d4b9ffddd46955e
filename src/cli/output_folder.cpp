#include "sdf_tracker/cli/output_folder.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <stdexcept>

#include "sdf_tracker/io/files.h"

namespace sdf_tracker::tools {

namespace fs = std::filesystem;

namespace {

constexpr const char* kStagingPrefix = ".sdf_tracker_staging-";

/// True while a process with this id runs (a staging folder of a live run is left alone).
bool processRuns(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM); }

}  // namespace

OutputFolder::OutputFolder(const std::string& directory, std::vector<std::string> results)
    : directory_(directory), results_(std::move(results)) {
  if (directory.empty()) throw std::invalid_argument("--output must name a folder (got an empty path)");
  io::makeDirectories(directory_);
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(directory_, error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(kStagingPrefix, 0) != 0) continue;
    const std::string pid = name.substr(std::string(kStagingPrefix).size());
    if (pid.empty() || !std::all_of(pid.begin(), pid.end(), ::isdigit) || processRuns(std::stol(pid))) continue;
    fs::remove_all(entry.path(), error);  // left by a killed run
  }
  staging_ = (fs::path(directory_) / (kStagingPrefix + std::to_string(::getpid()))).string();
  fs::remove_all(staging_, error);
  io::makeDirectories(staging_);
}

OutputFolder::~OutputFolder() {
  if (committed_) return;
  std::error_code error;
  fs::remove_all(staging_, error);
}

std::string OutputFolder::path(const std::string& name) const { return (fs::path(staging_) / name).string(); }

void OutputFolder::commit(const std::vector<std::string>& last) {
  // The previous run's results go first, its summaries before anything else.
  for (const auto& name : last) fs::remove(fs::path(directory_) / name);
  for (const auto& name : results_) fs::remove(fs::path(directory_) / name);
  auto move = [this](const std::string& name) {
    const fs::path from = fs::path(staging_) / name;
    if (fs::exists(from)) fs::rename(from, fs::path(directory_) / name);
  };
  for (const auto& name : results_) {
    if (std::find(last.begin(), last.end(), name) == last.end()) move(name);
  }
  for (const auto& name : last) move(name);
  fs::remove_all(staging_);
  committed_ = true;
}

}  // namespace sdf_tracker::tools
