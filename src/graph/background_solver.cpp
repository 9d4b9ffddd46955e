#include "sdf_tracker/graph/background_solver.h"

#include <utility>

namespace sdf_tracker {

BackgroundGraphSolver::BackgroundGraphSolver(const PoseGraphOptions& options) : options_(options) {
  const std::string invalid = options_.validate();
  if (!invalid.empty()) throw std::invalid_argument("pose graph options: " + invalid);
}

BackgroundGraphSolver::~BackgroundGraphSolver() { cancel(); }

void BackgroundGraphSolver::solve(PoseGraph graph) {
  queued_ = std::move(graph);
  if (!running_.valid()) startQueued();
}

void BackgroundGraphSolver::startQueued() {
  if (!queued_) return;
  running_ = std::async(std::launch::async, [graph = std::move(*queued_), options = options_]() mutable {
    const auto start = std::chrono::steady_clock::now();
    Result result;
    result.solution = graph.optimise(options);
    result.solve_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    result.graph = std::move(graph);
    return result;
  });
  queued_.reset();
}

std::optional<BackgroundGraphSolver::Result> BackgroundGraphSolver::poll() {
  if (!running_.valid() || running_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
    return std::nullopt;
  }
  Result result = running_.get();
  startQueued();
  return result;
}

std::optional<BackgroundGraphSolver::Result> BackgroundGraphSolver::finish() {
  std::optional<Result> newest;
  while (running_.valid()) {
    newest = running_.get();
    startQueued();
  }
  return newest;
}

void BackgroundGraphSolver::cancel() {
  queued_.reset();
  if (running_.valid()) running_.wait();
  running_ = std::future<Result>();
}

}  // namespace sdf_tracker
