#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace sdf_tracker {

/// Information (inverse covariance) of a relative pose, over the error (translation in metres,
/// rotation vector in radians) of T_measured^-1 * T_estimated, i.e. in the frame of the `to` node
/// as measured.
using PoseInformation = Eigen::Matrix<double, 6, 6>;

/// Why `information` cannot be an edge's ("" when it can): "not finite", "not symmetric", "not
/// positive definite". The one rule for PoseGraph::addEdge and a saved graph's reader.
std::string informationProblem(const PoseInformation& information);

/// The standard deviations `information` states along its least certain direction of translation
/// [m] and of rotation [degrees]: the square roots of the largest eigenvalues of its covariance's
/// two blocks. Along a direction it holds nothing (kUnconstrainedVariance), about a kilometre.
struct PoseSigma {
  double m = 0.0;
  double deg = 0.0;
};
PoseSigma leastCertainSigma(const PoseInformation& information);

/// What an edge of the pose graph was measured by.
enum class PoseEdgeKind {
  kOdometry,  ///< consecutive nodes, from tracking (or a robot's odometry): trusted as measured
  kLoop,      ///< a place found again: may be wrong, so it is held by a robust loss and may be rejected
};

/// A measured relative pose between two nodes: where `to` is in `from`'s frame.
struct PoseEdge {
  int from = 0;
  int to = 0;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();
  PoseInformation information = PoseInformation::Identity();
  PoseEdgeKind kind = PoseEdgeKind::kOdometry;
};

struct PoseGraphOptions {
  /// A loop edge whose squared Mahalanobis residual exceeds this after a solve is rejected and the
  /// graph solved again without it: 22.46 is the chi-square 99.9 % bound of 6 degrees of freedom,
  /// so a right loop is kept unless it is more than ~4.7 sigma off.
  double loop_rejection_chi2 = 22.46;
  /// Scale of the Cauchy loss on loop edges, in sigma: residuals beyond it weigh ever less, so a wrong
  /// loop bends the graph little before it is rejected.
  double loop_loss_sigma = 3.0;
  int max_iterations = 100;
  /// Loops rejected in one optimisation, at most (each costs a solve).
  int max_rejected_loops = 5;

  /// Each violated constraint, naming the field and its value ("" if valid).
  std::string validate() const;
};

struct PoseGraphSolution {
  std::vector<Eigen::Isometry3d> poses;  ///< T_map_node of each node, node 0 held where it was
  std::vector<int> rejected_loops;       ///< indices into edges() of loop edges found wrong
  double initial_cost = 0.0;             ///< half the sum of squared whitened residuals, before
  double final_cost = 0.0;               ///< and after (rejected loops left out of both)
  int iterations = 0;                    ///< over all rounds
  bool converged = false;
};

/// A pose graph: nodes are poses in the map frame (a submap's), edges measured relative poses
/// between them. optimise() finds the poses that agree best with every edge (least squares in the
/// edges' information, solved by Ceres), holding node 0 fixed to fix the map frame; loop edges sit
/// behind a Cauchy loss, and one that still disagrees after a solve (loop_rejection_chi2) is
/// rejected and the graph solved again without it, so one wrong loop cannot bend the map. Every
/// node is expected to be joined to node 0 through edges (a part that is not floats freely).
class PoseGraph {
 public:
  /// Adds a node at T_map_node (the initial guess); returns its index.
  int addNode(const Eigen::Isometry3d& T_map_node);
  /// Moves node `node` to T_map_node (where the next solve starts from, as a solution placed it);
  /// throws std::out_of_range for no such node.
  void setPose(int node, const Eigen::Isometry3d& T_map_node);
  /// Throws std::invalid_argument naming the edge's problem: a node that does not exist, an edge from
  /// a node to itself, or an information matrix that is not symmetric positive definite or finite.
  void addEdge(const PoseEdge& edge);

  const std::vector<Eigen::Isometry3d>& poses() const { return poses_; }
  const std::vector<PoseEdge>& edges() const { return edges_; }

  /// Solves the graph from its current poses; the graph itself is left unchanged. Throws
  /// std::invalid_argument for invalid options.
  PoseGraphSolution optimise(const PoseGraphOptions& options = {}) const;

  /// The whitened residual of `edge` at the given poses: the measured relative pose's error,
  /// (translation, rotation vector) of T_measured^-1 * T_from^-1 * T_to, times the information's
  /// square root; its squared norm is the edge's squared Mahalanobis distance.
  static Eigen::Matrix<double, 6, 1> whitenedResidual(const PoseEdge& edge,
                                                      const std::vector<Eigen::Isometry3d>& poses);

 private:
  std::vector<Eigen::Isometry3d> poses_;
  std::vector<PoseEdge> edges_;
};

}  // namespace sdf_tracker
