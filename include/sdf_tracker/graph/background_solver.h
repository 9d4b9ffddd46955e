#pragma once

#include <chrono>
#include <future>
#include <optional>

#include "sdf_tracker/graph/pose_graph.h"

namespace sdf_tracker {

/// Solves pose graphs on a thread of its own, so that whoever adds the edges (the tracking loop)
/// never waits for Ceres: solve() hands over a copy of the graph and returns at once, poll() gives
/// the solution once it is there. One solve runs at a time; a graph handed over while one runs is
/// solved next, and a newer one replaces it (it holds every edge the older one did). Not thread
/// safe itself: one caller.
class BackgroundGraphSolver {
 public:
  explicit BackgroundGraphSolver(const PoseGraphOptions& options = {});
  /// Waits for a solve still running (its result is dropped).
  ~BackgroundGraphSolver();
  BackgroundGraphSolver(const BackgroundGraphSolver&) = delete;
  BackgroundGraphSolver& operator=(const BackgroundGraphSolver&) = delete;

  struct Result {
    PoseGraph graph;            ///< what was solved: its nodes and edges
    PoseGraphSolution solution;
    double solve_ms = 0.0;      ///< wall time of the solve
  };

  /// Solves `graph` in the background (after the running solve, if any).
  void solve(PoseGraph graph);
  /// The finished solve's result, if one has finished since the last call; never waits.
  std::optional<Result> poll();
  /// Waits until every graph handed over is solved; the newest solution, if any was pending.
  std::optional<Result> finish();
  /// A solve is running or waiting to run.
  bool busy() const { return running_.valid() || queued_.has_value(); }
  /// Drops whatever is queued and waits for a running solve, whose result is dropped too.
  void cancel();

 private:
  void startQueued();

  PoseGraphOptions options_;
  std::future<Result> running_;
  std::optional<PoseGraph> queued_;
};

}  // namespace sdf_tracker
