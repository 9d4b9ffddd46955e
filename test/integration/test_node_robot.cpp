// What a robot reads from the running node of node.test (the fixture of node_test.h): ~odom as
// robot_localization's EKF takes it, and /diagnostics as rqt_robot_monitor shows it.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>

#include "node_test.h"

namespace node_test {
namespace {

using Covariance = Eigen::Matrix<double, 6, 6>;

Covariance fromRowMajor(const boost::array<double, 36>& values) {
  Covariance c;
  for (int r = 0; r < 6; ++r) {
    for (int k = 0; k < 6; ++k) c(r, k) = values[6 * r + k];
  }
  return c;
}

class NodeRobotTest : public NodeTest {
 protected:
  void SetUp() override {
    NodeTest::SetUp();
    odom_sub_ = nh_.subscribe("sdf_tracker/odom", 50, &NodeRobotTest::onOdom, this);
    diagnostics_sub_ = nh_.subscribe("/diagnostics", 50, &NodeRobotTest::onDiagnostics, this);
    for (int i = 0; i < 50 && (odom_sub_.getNumPublishers() == 0 || diagnostics_sub_.getNumPublishers() == 0); ++i) {
      ros::Duration(0.1).sleep();
    }
  }
  void onOdom(const nav_msgs::Odometry& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    odoms_.push_back(msg);
  }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& status : msg.status) diagnostics_[status.name] = status;
  }
  /// The ~odom message for the frame stamped `stamp`, waiting a little for it.
  std::optional<nav_msgs::Odometry> odomAt(const ros::Time& stamp) {
    for (int i = 0; i < 20; ++i) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const auto& odom : odoms_) {
          if (odom.header.stamp == stamp) return odom;
        }
      }
      ros::Duration(0.05).sleep();
    }
    return std::nullopt;
  }

  ros::Subscriber odom_sub_, diagnostics_sub_;
  std::vector<nav_msgs::Odometry> odoms_;
  std::map<std::string, diagnostic_msgs::DiagnosticStatus> diagnostics_;
};

TEST_F(NodeRobotTest, OdometryCarriesThePoseWithAPositiveDefiniteCovarianceAndTheDiagnosticsSayTracking) {
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  sdf_tracker::TrackingStatus status;
  for (int i = 0; i < 10; ++i) {
    status = publishDeskFrame(1000.0 + i / 30.0, i / 30.0);
    ASSERT_EQ(status.status, sdf_tracker::TrackingStatus::OK) << status.status_text;
  }
  const std::optional<nav_msgs::Odometry> odom = odomAt(status.header.stamp);
  ASSERT_TRUE(odom) << "no ~odom for a tracked frame";
  EXPECT_EQ(odom->header.frame_id, "map");
  EXPECT_EQ(odom->child_frame_id, "camera_depth_optical_frame") << "the camera: node.test sets no base_frame";
  const Covariance pose = fromRowMajor(odom->pose.covariance);
  EXPECT_TRUE(pose.isApprox(pose.transpose())) << pose;
  EXPECT_EQ(Eigen::LLT<Covariance>(pose).info(), Eigen::Success) << "positive definite:\n" << pose;
  const double position_sigma_m = std::sqrt(pose.topLeftCorner<3, 3>().trace());
  std::cout << "[ figures  ] ~odom position sigma " << position_sigma_m * 1000 << " mm\n";
  EXPECT_LT(position_sigma_m, 0.01) << "the room constrains every direction";
  EXPECT_EQ(Eigen::LLT<Covariance>(fromRowMajor(odom->twist.covariance)).info(), Eigen::Success);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto same = std::find_if(poses_.begin(), poses_.end(), [&](const st::io::StampedPose& p) {
      return std::abs(p.timestamp_s - status.header.stamp.toSec()) < 1e-6;
    });
    ASSERT_NE(same, poses_.end());
    EXPECT_TRUE(same->T_W_C.isApprox(sdf_tracker_ros::fromPoseMsg(odom->pose.pose), 1e-9)) << "~odom is ~pose";
  }

  // The diagnostics go out once a second.
  ros::Duration(1.5).sleep();
  std::lock_guard<std::mutex> lock(mutex_);
  const auto tracking = diagnostics_.find("sdf_tracker: tracking");
  const auto frames = diagnostics_.find("sdf_tracker: frames");
  ASSERT_NE(tracking, diagnostics_.end()) << "no tracking diagnostics";
  ASSERT_NE(frames, diagnostics_.end()) << "no frame diagnostics";
  EXPECT_EQ(tracking->second.level, diagnostic_msgs::DiagnosticStatus::OK) << tracking->second.message;
  EXPECT_NE(frames->second.hardware_id.find("depth/image"), std::string::npos) << frames->second.hardware_id;
}

TEST_F(NodeRobotTest, AlongASingleWallTheOdometryStatesWhatTheViewDoesNotConstrain) {
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  st::synthetic::NoiseModel exact;
  exact.enabled = false;
  const st::DepthImage wall = st::synthetic::Scene::singleWall().render(kQvga, Eigen::Isometry3d::Identity(), exact, 0);
  sdf_tracker::TrackingStatus status;
  for (int i = 0; i < 4; ++i) {
    std_msgs::Header header;
    header.stamp = ros::Time(1100.0 + i / 30.0);
    header.frame_id = "camera_depth_optical_frame";
    status = publishAndWait(sdf_tracker_ros::toImageMsg(wall, header), kQvga);
  }
  ASSERT_EQ(status.status, sdf_tracker::TrackingStatus::DEGENERATE) << status.status_text;
  ASSERT_EQ(status.constrained_rank, 3) << "distance and two tilts";
  const std::optional<nav_msgs::Odometry> odom = odomAt(status.header.stamp);
  ASSERT_TRUE(odom) << "a degenerate frame is tracked in its constrained directions and published";
  const Covariance pose = fromRowMajor(odom->pose.covariance);
  std::cout << "[ figures  ] ~odom variances on a wall: " << pose.diagonal().transpose() << "\n";
  // The camera looks along map x at the wall: x and the tilts are seen; y, z and the turn about x
  // are not.
  EXPECT_LT(pose(0, 0), 1e-4) << "towards the wall";
  EXPECT_GT(pose(1, 1), 1e4) << "along the wall, sideways";
  EXPECT_GT(pose(2, 2), 1e4) << "along the wall, up";
  EXPECT_GT(pose(3, 3), 1e3) << "about the wall's normal";
  EXPECT_EQ(Eigen::LLT<Covariance>(pose).info(), Eigen::Success);
}

}  // namespace
}  // namespace node_test
