// Drives the real sdf_tracker_node with a bag that tum_to_bag made from a synthetic QVGA sequence
// (image + its own camera_info), frame by frame in lock-step with the node's ~status; checks tf,
// path, cloud, accuracy against the offline pipeline on the same frames, bad input, frames from the
// past and frames with a parent already, and the executables' refusals. The services and
// reconfiguration are in test_node_services.cpp (the same binary).

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "node_test.h"
#include "run_command.h"

namespace node_test {
namespace {

TEST_F(NodeTest, TracksAQvgaBagLikeTheOfflineRunnerAndSurvivesBadInput) {
  const int frames = ros::NodeHandle("~").param("frames", 60);
  char pattern[] = "/tmp/sdf_tracker_node_test_XXXXXX";
  ASSERT_NE(mkdtemp(pattern), nullptr);
  const std::string directory = pattern;
  const std::string bag_path = makeSyntheticBag(directory, frames);
  const st::TumSequence sequence = st::TumSequence::open(directory);

  // The offline pipeline with the node's settings (default preset, 160^3 grid), same frames.
  st::Settings settings = st::preset("default");
  settings.pipeline.volume.dims = Eigen::Vector3i(160, 160, 160);
  st::SdfPipeline offline(settings.pipeline);
  std::vector<st::io::StampedPose> offline_trajectory;
  for (size_t i = 0; i < sequence.size(); ++i) {
    offline.processFrame(sequence.depth(i), sequence.camera(), sequence.timestamp(i));
    offline_trajectory.push_back({sequence.timestamp(i), offline.pose()});
  }

  // Play the bag frame by frame: each image with its camera_info, waiting for the node's status.
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{"/camera/depth/image", "/camera/depth/camera_info"}));
  std::map<ros::Time, sensor_msgs::CameraInfoConstPtr> infos;
  for (const rosbag::MessageInstance& m : view) {
    if (const auto info = m.instantiate<sensor_msgs::CameraInfo>()) infos[info->header.stamp] = info;
  }
  double time_offset = 0.0;
  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);
  int played = 0;
  ros::Time last_stamp;
  for (const rosbag::MessageInstance& m : view) {
    const auto image = m.instantiate<sensor_msgs::Image>();
    if (!image) continue;
    ASSERT_TRUE(infos.count(image->header.stamp)) << "the bag pairs every image with a camera_info";
    const sensor_msgs::CameraInfoConstPtr info = infos[image->header.stamp];
    time_offset = image->header.stamp.toSec() - sequence.timestamp(played);
    const auto status = publishAndWait(*image, sdf_tracker_ros::toCamera(*info));
    EXPECT_EQ(status.status, sdf_tracker::TrackingStatus::OK) << "frame " << played << ": " << status.status_text;
    EXPECT_EQ(status.header.stamp, image->header.stamp) << "outputs carry the input's stamp";
    last_stamp = image->header.stamp;
    if (++played == frames / 2) {  // a frame in an encoding the node cannot read: dropped, node alive
      sensor_msgs::Image colour = *image;
      colour.encoding = "rgb8";
      colour.header.stamp += ros::Duration(0.01);
      const auto bad = publishAndWait(colour, sdf_tracker_ros::toCamera(*info));
      EXPECT_EQ(bad.status, sdf_tracker::TrackingStatus::BAD_INPUT);
      EXPECT_NE(bad.status_text.find("rgb8"), std::string::npos) << bad.status_text;
    }
  }
  ASSERT_EQ(played, frames);
  ros::Duration(1.5).sleep();  // the cloud timer runs at 2 Hz

  std::lock_guard<std::mutex> lock(mutex_);
  EXPECT_EQ(static_cast<int>(poses_.size()), frames);
  EXPECT_EQ(static_cast<int>(path_length_), frames);
  EXPECT_GT(cloud_points_, 1000u);
  EXPECT_TRUE(tf_buffer.canTransform("map", "openni_depth_optical_frame", last_stamp))
      << "tf map -> camera at the last frame's stamp";

  std::vector<st::io::StampedPose> node_trajectory = poses_;
  for (auto& pose : node_trajectory) pose.timestamp_s -= time_offset;
  const double node_ate = st::evaluation::computeAte(node_trajectory, sequence.groundTruth()).translation_m.rmse;
  const double offline_ate = st::evaluation::computeAte(offline_trajectory, sequence.groundTruth()).translation_m.rmse;
  std::cout << "[ figures  ] node ATE " << node_ate * 1000 << " mm, offline ATE " << offline_ate * 1000 << " mm\n";
  EXPECT_LT(std::abs(node_ate - offline_ate), kMaxAteDifference_m);
}


TEST_F(NodeTest, AFrameFromThePastIsDroppedWithoutWipingTheMap) {
  ASSERT_TRUE(ros::service::call("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  for (int i = 0; i < 3; ++i) publishDeskFrame(300.0 + i / 30.0, i / 30.0);
  const size_t poses_before = poses_.size();
  // A stray frame stamped 0.5 s (a restarted clock): dropped and said, the map and path kept.
  const auto stray = publishDeskFrame(0.5, 3 / 30.0);
  EXPECT_EQ(stray.status, sdf_tracker::TrackingStatus::BAD_INPUT);
  EXPECT_NE(stray.status_text.find("before the last frame"), std::string::npos) << stray.status_text;
  const auto next = publishDeskFrame(300.0 + 4 / 30.0, 4 / 30.0);
  EXPECT_EQ(next.status, sdf_tracker::TrackingStatus::OK) << next.status_text << ": the map is still there";
  ros::Duration(0.3).sleep();
  std::lock_guard<std::mutex> lock(mutex_);
  EXPECT_EQ(poses_.size(), poses_before + 1);
  EXPECT_EQ(path_length_, 4u) << "the path holds the four tracked frames since the reset";
}

TEST_F(NodeTest, AHeldPoseGoesOutOnNeitherPoseNorPath) {
  // Issue 44: after a loss ~pose and the trajectory carried frozen copies of the held pose, which an
  // evaluator or a planner cannot tell from estimates (README: "Estimates and held poses").
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  for (int i = 0; i < 3; ++i) publishDeskFrame(800.0 + i / 30.0, i / 30.0);
  ros::Duration(0.3).sleep();
  size_t poses_before;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    poses_before = poses_.size();
  }
  // A wall 7.5 m away, far beyond the mapped room: tracking fails and the pose is held (two frames:
  // a brief loss, after which a fit from the held pose is taken at once).
  std_msgs::Header header;
  header.frame_id = "camera_depth_optical_frame";
  for (int i = 0; i < 2; ++i) {
    header.stamp = ros::Time(800.0 + (3 + i) / 30.0);
    const auto held = publishAndWait(sdf_tracker_ros::toImageMsg(st::DepthImage(kQvga.width, kQvga.height, 7.5f), header), kQvga);
    EXPECT_NE(held.status, sdf_tracker::TrackingStatus::OK) << held.status_text;
    EXPECT_FALSE(held.fused) << held.status_text;
  }
  const auto back = publishDeskFrame(800.0 + 5 / 30.0, 3 / 30.0);
  EXPECT_EQ(back.status, sdf_tracker::TrackingStatus::OK) << back.status_text;
  ros::Duration(0.3).sleep();
  std::lock_guard<std::mutex> lock(mutex_);
  EXPECT_EQ(poses_.size(), poses_before + 1) << "only the frame tracked again goes out on ~pose";
  EXPECT_EQ(path_length_, 4u) << "the path holds the four estimates since the reset";
}

TEST_F(NodeTest, NeverGivesAFrameThatHasAParentASecondOne) {
  // Another publisher already gives the image's frame a parent (as a camera driver's chain does).
  const std::string frame = "mounted_optical_frame";
  tf2_ros::StaticTransformBroadcaster static_broadcaster;
  geometry_msgs::TransformStamped mount;
  mount.header.stamp = ros::Time(1.0);
  mount.header.frame_id = "camera_mount";
  mount.child_frame_id = frame;
  mount.transform.rotation.w = 1.0;
  static_broadcaster.sendTransform(mount);
  std::set<std::string> parents_given_by_others, parents_seen;
  std::mutex tf_mutex;
  ros::Subscriber tf_sub = nh_.subscribe<tf2_msgs::TFMessage>("/tf", 100, [&](const tf2_msgs::TFMessageConstPtr& msg) {
    std::lock_guard<std::mutex> lock(tf_mutex);
    for (const auto& tf : msg->transforms) {
      if (tf.child_frame_id == frame) parents_seen.insert(tf.header.frame_id);
    }
  });
  ros::Duration(1.0).sleep();  // the node's tf listener hears the static transform
  ASSERT_TRUE(ros::service::call("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));

  const size_t poses_before = poses_.size();
  for (int i = 0; i < 3; ++i) {
    publishAndWait(deskFrame(200.0 + i, 0.1 * i, "/" + frame), kQvga);  // a leading slash, as in the TUM bags
  }
  ros::Duration(0.5).sleep();
  std::lock_guard<std::mutex> lock(tf_mutex);
  EXPECT_TRUE(parents_seen.empty()) << "the node published a parent for " << frame << ": " << *parents_seen.begin();
  EXPECT_GE(poses_.size(), poses_before + 3) << "the estimate still goes out on ~pose";
}

// The tracker refuses to start on a TUM camera it does not know, on two sources of intrinsics or
// on frames that cannot form a tree, and says which parameter and value; nothing is guessed.
TEST(TrackerNode, RefusesAnUnknownTumCameraTwoSourcesOfIntrinsicsAndFramesThatCannotFormATreeByName) {
  // A private parameter given on the command line stays on the parameter server after the node
  // exits: each case runs under a name of its own.
  auto node = [](const std::string& name) {
    return "timeout 30 rosrun sdf_tracker sdf_tracker_node __name:=" + name + " ";
  };
  st::test::CommandResult run = st::test::runCommand(node("unknown_tum_camera") + "_tum_camera:=freiburg4");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("~tum_camera must be one of freiburg1, freiburg2, freiburg3, or empty for camera_info's "
                            "calibration (got \"freiburg4\")"),
            std::string::npos)
      << run.output;
  run = st::test::runCommand(node("empty_map_frame") + "_map_frame:=''");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("~map_frame must name a frame (got \"\")"), std::string::npos) << run.output;
  run = st::test::runCommand(node("odom_frame_is_map") + "_odom_frame:=map");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("~map_frame and ~odom_frame are both \"map\": a frame cannot be its own parent"),
            std::string::npos)
      << run.output;
  run = st::test::runCommand(node("two_intrinsics") + "_tum_camera:=freiburg1 _FocalLengthX:=500.0");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("~tum_camera (freiburg1) and FocalLength/CenterPoint both give the intrinsics"),
            std::string::npos)
      << run.output;
}

// A file that could not be written at shut-down is refused at the start, naming the parameter;
// one that can is written at shut-down (SIGINT, as roslaunch stops a node) and said so on stdout.
TEST(TrackerNode, OutputFilesAreCheckedAtTheStartAndReportedAtShutDown) {
  const std::string node = "rosrun sdf_tracker sdf_tracker_node ";
  st::test::CommandResult run = st::test::runCommand(
      "timeout 30 " + node + "__name:=missing_output_folder _trajectory_file:=/nonexistent/folder/trajectory.txt");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("~trajectory_file \"/nonexistent/folder/trajectory.txt\": the folder /nonexistent/folder "
                            "does not exist"),
            std::string::npos)
      << run.output;

  char folder[] = "/tmp/sdf_tracker_output_check_XXXXXX";
  ASSERT_NE(mkdtemp(folder), nullptr);
  const std::string trajectory = std::string(folder) + "/trajectory.txt";
  run = st::test::runCommand("timeout --preserve-status -s INT 8 " + node +
                             "__name:=written_at_shut_down _trajectory_file:=" + trajectory);
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("sdf_tracker: wrote the trajectory to " + trajectory), std::string::npos) << run.output;
  EXPECT_TRUE(std::ifstream(trajectory).good()) << trajectory << " was not written";
}

// The camera drivers on a machine without a camera, or pointed at a recording that is not there:
// an error that names what is missing, and a non-zero exit (roslaunch then ends the launch).
TEST(CameraDrivers, WithoutACameraOrRecordingExitWithAnErrorNamingIt) {
  const std::string driver = "ROS_NAMESPACE=no_camera timeout 30 rosrun sdf_tracker ";
  st::test::CommandResult run = st::test::runCommand(driver + "openni2_depth_publisher");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("no OpenNI 2 camera found"), std::string::npos) << run.output;

  run = st::test::runCommand(driver + "openni2_depth_publisher _device_id:=/nonexistent/recording.oni");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("cannot open ~device_id \"/nonexistent/recording.oni\""), std::string::npos) << run.output;

  run = st::test::runCommand(driver + "openni2_depth_publisher _depth_mode:=HD");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("~depth_mode must be VGA or QVGA (got \"HD\")"), std::string::npos) << run.output;

  run = st::test::runCommand(driver + "kinect_depth_publisher");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_TRUE(run.output.find("no Kinect found") != std::string::npos ||
              run.output.find("libfreenect failed to initialise") != std::string::npos)
      << run.output;

  // Through libfreenect's own replay wrapper, as kinect.launch fakenect:= runs it.
  run = st::test::runCommand("ROS_NAMESPACE=no_camera timeout 30 fakenect /nonexistent/dump rosrun sdf_tracker kinect_depth_publisher");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("FAKENECT_PATH=/nonexistent/dump: cannot open /nonexistent/dump/INDEX.txt"), std::string::npos)
      << run.output;

  // A recording whose calibration file cannot be read: refused, not replayed with a guess.
  char dump[] = "/tmp/sdf_tracker_corrupt_calibration_XXXXXX";
  ASSERT_NE(mkdtemp(dump), nullptr);
  std::ofstream(std::string(dump) + "/INDEX.txt") << "d-1.000000-0.pgm\n";
  std::ofstream(std::string(dump) + "/depth_camera_info.yaml") << "image_width: [not, a, number\n";
  run = st::test::runCommand("ROS_NAMESPACE=no_camera timeout 30 fakenect " + std::string(dump) +
                             " rosrun sdf_tracker kinect_depth_publisher");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("the recording's depth calibration " + std::string(dump) +
                            "/depth_camera_info.yaml cannot be read as a camera calibration"),
            std::string::npos)
      << run.output;
}


}  // namespace
}  // namespace node_test


int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sdf_tracker_node_test");
  return RUN_ALL_TESTS();
}
