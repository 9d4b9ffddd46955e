#include "sdf_tracker/graph/pose_graph.h"

#include <ceres/ceres.h>
#include <ceres/manifold.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace sdf_tracker {
namespace {

/// The error of one edge for Ceres: each node a translation (3) and a unit quaternion (x, y, z, w,
/// Eigen's order), whitened by the square root of the edge's information.
class RelativePoseError {
 public:
  RelativePoseError(const Eigen::Isometry3d& T_from_to, const PoseInformation& sqrt_information)
      : t_measured_(T_from_to.translation()), q_measured_(T_from_to.rotation()), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* t_from, const T* q_from, const T* t_to, const T* q_to, T* residual) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(t_from), p_b(t_to);
    const Eigen::Map<const Eigen::Quaternion<T>> r_a(q_from), r_b(q_to);
    const Eigen::Quaternion<T> r_a_inverse = r_a.conjugate();
    const Eigen::Quaternion<T> r_ab = r_a_inverse * r_b;
    const Eigen::Matrix<T, 3, 1> p_ab = r_a_inverse * (p_b - p_a);
    const Eigen::Quaternion<T> r_measured_inverse = q_measured_.conjugate().template cast<T>();
    Eigen::Quaternion<T> r_error = r_measured_inverse * r_ab;
    if (r_error.w() < T(0)) r_error.coeffs() = -r_error.coeffs();  // the short way round
    Eigen::Matrix<T, 6, 1> error;
    error.template head<3>() = r_measured_inverse * (p_ab - t_measured_.cast<T>());
    error.template tail<3>() = T(2) * r_error.vec();  // the rotation vector, to first order
    Eigen::Map<Eigen::Matrix<T, 6, 1>> whitened(residual);
    whitened = sqrt_information_.cast<T>() * error;
    return true;
  }

 private:
  Eigen::Vector3d t_measured_;
  Eigen::Quaterniond q_measured_;
  PoseInformation sqrt_information_;
};

/// L^T of information = L L^T, so that |L^T e|^2 = e^T information e.
PoseInformation sqrtInformation(const PoseInformation& information) { return information.llt().matrixL().transpose(); }

std::string describeEdge(const PoseEdge& edge) {
  std::ostringstream out;
  out << (edge.kind == PoseEdgeKind::kLoop ? "loop" : "odometry") << " edge " << edge.from << " -> " << edge.to;
  return out.str();
}

struct NodeParameters {
  Eigen::Vector3d t;
  Eigen::Quaterniond q;
};

}  // namespace

std::string PoseGraphOptions::validate() const {
  std::ostringstream out;
  if (!(loop_rejection_chi2 > 0.0)) out << "loop_rejection_chi2 must be > 0, got " << loop_rejection_chi2 << "; ";
  if (!(loop_loss_sigma > 0.0)) out << "loop_loss_sigma must be > 0, got " << loop_loss_sigma << "; ";
  if (max_iterations < 1) out << "max_iterations must be >= 1, got " << max_iterations << "; ";
  if (max_rejected_loops < 0) out << "max_rejected_loops must be >= 0, got " << max_rejected_loops << "; ";
  return out.str();
}

int PoseGraph::addNode(const Eigen::Isometry3d& T_map_node) {
  poses_.push_back(T_map_node);
  return static_cast<int>(poses_.size()) - 1;
}

void PoseGraph::setPose(int node, const Eigen::Isometry3d& T_map_node) {
  if (node < 0 || node >= static_cast<int>(poses_.size())) {
    throw std::out_of_range("pose graph: no node " + std::to_string(node) + " (there are " +
                            std::to_string(poses_.size()) + ")");
  }
  poses_[node] = T_map_node;
}

PoseSigma leastCertainSigma(const PoseInformation& information) {
  const Eigen::Matrix<double, 6, 6> covariance = information.ldlt().solve(Eigen::Matrix<double, 6, 6>::Identity());
  const auto largest = [](const Eigen::Matrix3d& block) {
    return std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(0.5 * (block + block.transpose()))
                                       .eigenvalues()
                                       .maxCoeff()));
  };
  return {largest(covariance.topLeftCorner<3, 3>()), largest(covariance.bottomRightCorner<3, 3>()) * 180.0 / M_PI};
}

std::string informationProblem(const PoseInformation& information) {
  if (!information.allFinite()) return "not finite";
  if (!information.isApprox(information.transpose(), 1e-9)) return "not symmetric";
  if (information.llt().info() != Eigen::Success) return "not positive definite";
  return "";
}

void PoseGraph::addEdge(const PoseEdge& edge) {
  const int nodes = static_cast<int>(poses_.size());
  auto refuse = [&edge](const std::string& why) { throw std::invalid_argument(describeEdge(edge) + ": " + why); };
  if (edge.from < 0 || edge.from >= nodes || edge.to < 0 || edge.to >= nodes) {
    refuse("the graph has nodes 0 to " + std::to_string(nodes - 1));
  }
  if (edge.from == edge.to) refuse("an edge joins two different nodes");
  if (!edge.T_from_to.matrix().allFinite()) refuse("the relative pose is not finite");
  if (const std::string why = informationProblem(edge.information); !why.empty()) {
    refuse("the information matrix is " + why);
  }
  edges_.push_back(edge);
}

Eigen::Matrix<double, 6, 1> PoseGraph::whitenedResidual(const PoseEdge& edge,
                                                        const std::vector<Eigen::Isometry3d>& poses) {
  const Eigen::Isometry3d T_error = edge.T_from_to.inverse() * poses.at(edge.from).inverse() * poses.at(edge.to);
  const Eigen::AngleAxisd rotation(T_error.rotation());
  Eigen::Matrix<double, 6, 1> error;
  error << T_error.translation(), rotation.angle() * rotation.axis();
  return sqrtInformation(edge.information) * error;
}

PoseGraphSolution PoseGraph::optimise(const PoseGraphOptions& options) const {
  if (const std::string problems = options.validate(); !problems.empty()) {
    throw std::invalid_argument("pose graph options: " + problems);
  }
  PoseGraphSolution solution;
  std::vector<bool> rejected(edges_.size(), false);
  for (int round = 0;; ++round) {
    // Every round starts from the graph's own poses, so a rejected loop leaves no trace.
    std::vector<NodeParameters> nodes(poses_.size());
    for (size_t i = 0; i < poses_.size(); ++i) {
      nodes[i].t = poses_[i].translation();
      nodes[i].q = Eigen::Quaterniond(poses_[i].rotation()).normalized();
    }
    ceres::Problem problem;
    for (size_t e = 0; e < edges_.size(); ++e) {
      if (rejected[e]) continue;
      const PoseEdge& edge = edges_[e];
      auto* cost = new ceres::AutoDiffCostFunction<RelativePoseError, 6, 3, 4, 3, 4>(
          new RelativePoseError(edge.T_from_to, sqrtInformation(edge.information)));
      // Cauchy's scale is on the squared residual: loop_loss_sigma^2.
      ceres::LossFunction* loss = edge.kind == PoseEdgeKind::kLoop
                                      ? new ceres::CauchyLoss(options.loop_loss_sigma * options.loop_loss_sigma)
                                      : nullptr;
      NodeParameters& a = nodes[edge.from];
      NodeParameters& b = nodes[edge.to];
      problem.AddResidualBlock(cost, loss, a.t.data(), a.q.coeffs().data(), b.t.data(), b.q.coeffs().data());
    }
    for (NodeParameters& node : nodes) {
      if (!problem.HasParameterBlock(node.q.coeffs().data())) continue;
      problem.SetManifold(node.q.coeffs().data(), new ceres::EigenQuaternionManifold);
    }
    if (!nodes.empty() && problem.HasParameterBlock(nodes[0].t.data())) {
      problem.SetParameterBlockConstant(nodes[0].t.data());
      problem.SetParameterBlockConstant(nodes[0].q.coeffs().data());
    }
    ceres::Solver::Options solver;
    solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver.max_num_iterations = options.max_iterations;
    solver.num_threads = 1;  // off the tracking thread, and not taking the tracker's cores
    solver.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    if (problem.NumResidualBlocks() > 0) ceres::Solve(solver, &problem, &summary);

    solution.poses.resize(poses_.size());
    for (size_t i = 0; i < poses_.size(); ++i) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = nodes[i].q.normalized().toRotationMatrix();
      T.translation() = nodes[i].t;
      solution.poses[i] = T;
    }
    solution.iterations += static_cast<int>(summary.iterations.size());
    solution.initial_cost = summary.initial_cost;
    solution.final_cost = summary.final_cost;
    solution.converged = problem.NumResidualBlocks() == 0 || summary.termination_type == ceres::CONVERGENCE;

    if (round == options.max_rejected_loops) break;
    // The loop that disagrees most, if any disagrees beyond the bound, is rejected and the graph
    // solved again: one at a time, since a wrong loop also pulls right ones off.
    int worst = -1;
    double worst_chi2 = options.loop_rejection_chi2;
    for (size_t e = 0; e < edges_.size(); ++e) {
      if (rejected[e] || edges_[e].kind != PoseEdgeKind::kLoop) continue;
      const double chi2 = whitenedResidual(edges_[e], solution.poses).squaredNorm();
      if (chi2 > worst_chi2) worst = static_cast<int>(e), worst_chi2 = chi2;
    }
    if (worst < 0) break;
    rejected[worst] = true;
    solution.rejected_loops.push_back(worst);
  }
  std::sort(solution.rejected_loops.begin(), solution.rejected_loops.end());
  return solution;
}

}  // namespace sdf_tracker
