// Drives the real sdf_tracker_node with a bag that tum_to_bag made from a synthetic QVGA sequence
// (image + its own camera_info), frame by frame in lock-step with the node's ~status; checks tf,
// path, cloud, accuracy against the offline pipeline on the same frames, bad input, frames from the
// past and frames with a parent already, colour images the node cannot use, and the executables'
// refusals. The services and reconfiguration are in test_node_services.cpp (the same binary).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <functional>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "node_test.h"
#include "run_command.h"
#include "scratch_directory.h"
#include "sdf_tracker/surface/surface.h"

namespace node_test {
namespace {

TEST_F(NodeTest, TracksAQvgaBagLikeTheOfflineRunnerAndSurvivesBadInput) {
  const int frames = ros::NodeHandle("~").param("frames", 60);
  const std::string directory = st::test::scratchDirectory("node_test");
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
  EXPECT_EQ(static_cast<int>(last_path_.poses.size()), frames);
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
  EXPECT_EQ(last_path_.poses.size(), 4u) << "the path holds the four tracked frames since the reset";
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
  EXPECT_EQ(last_path_.poses.size(), 4u) << "the path holds the four estimates since the reset";
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

/// The node of node.test with what colour images do to it: the colour topic it listens to (the
/// depth is registered to it, ~colour_registered), /diagnostics' "sdf_tracker: colour", the node's
/// warnings on /rosout and the whole of ~cloud.
class NodeColourTest : public NodeTest {
 protected:
  static constexpr const char* kColourTask = "sdf_tracker: colour";

  void SetUp() override {
    NodeTest::SetUp();
    colour_pub_ = nh_.advertise<sensor_msgs::Image>("camera/rgb/image_color", 5);
    diagnostics_sub_ = nh_.subscribe("/diagnostics", 50, &NodeColourTest::onDiagnostics, this);
    rosout_sub_ = nh_.subscribe("/rosout", 500, &NodeColourTest::onLog, this);
    full_cloud_sub_ = nh_.subscribe("sdf_tracker/cloud", 1, &NodeColourTest::onFullCloud, this);
    for (int i = 0; i < 100 && (colour_pub_.getNumSubscribers() == 0 || diagnostics_sub_.getNumPublishers() == 0 ||
                                rosout_sub_.getNumPublishers() == 0 || full_cloud_sub_.getNumPublishers() == 0);
         ++i) {
      ros::Duration(0.1).sleep();
    }
    ASSERT_GT(colour_pub_.getNumSubscribers(), 0u) << "the node does not listen to camera/rgb/image_color";
  }

  void onDiagnostics(const diagnostic_msgs::DiagnosticArray& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& status : msg.status) {
      if (status.name == kColourTask) colour_status_ = status;
    }
    changed_.notify_all();
  }
  void onLog(const rosgraph_msgs::Log& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (msg.name == "/sdf_tracker" && msg.level == rosgraph_msgs::Log::WARN) warnings_.push_back(msg.msg);
    changed_.notify_all();
  }
  void onFullCloud(const sensor_msgs::PointCloud2ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (msg->header.stamp == awaited_cloud_stamp_) {
      ++clouds_at_awaited_stamp_;
      awaited_cloud_ = msg;
    }
    changed_.notify_all();
  }

  /// `colour` stamped as the depth frame of the desk path at t_s it goes with, then that frame;
  /// waits for the node's status about the frame.
  sdf_tracker::TrackingStatus publishWithColour(sensor_msgs::Image colour, double stamp_s, double t_s) {
    colour.header.stamp = ros::Time(stamp_s);
    colour.header.frame_id = "camera_depth_optical_frame";  // registered to the depth
    colour_pub_.publish(colour);
    ros::Duration(0.1).sleep();  // in the node's cache of colour images before the frame is fused
    return publishDeskFrame(stamp_s, t_s);
  }

  /// The first "sdf_tracker: colour" status that `wanted` holds for, waiting up to
  /// kStatusTimeout_s; the last one heard when none does (an empty one when none came at all).
  diagnostic_msgs::DiagnosticStatus colourStatus(
      const std::function<bool(const diagnostic_msgs::DiagnosticStatus&)>& wanted) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait_for(lock, std::chrono::duration<double>(kStatusTimeout_s),
                      [&] { return colour_status_ && wanted(*colour_status_); });
    return colour_status_ ? *colour_status_ : diagnostic_msgs::DiagnosticStatus();
  }
  /// A diagnostic status's value of `key` as a count; -1 when it has none.
  static int count(const diagnostic_msgs::DiagnosticStatus& status, const std::string& key) {
    for (const auto& value : status.values) {
      if (value.key == key) return std::stoi(value.value);
    }
    return -1;
  }

  /// Whether the node warned, on /rosout, with a message holding every one of `parts`, waiting
  /// up to kStatusTimeout_s.
  bool warned(const std::vector<std::string>& parts) {
    auto holds = [&](const std::string& text) {
      return std::all_of(parts.begin(), parts.end(),
                         [&](const std::string& p) { return text.find(p) != std::string::npos; });
    };
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, std::chrono::duration<double>(kStatusTimeout_s),
                             [&] { return std::any_of(warnings_.begin(), warnings_.end(), holds); });
  }

  /// The second ~cloud stamped `stamp` (the first may be of a snapshot taken before that frame was
  /// fused), waiting up to kStatusTimeout_s; nullptr when none came.
  sensor_msgs::PointCloud2ConstPtr cloudAt(const ros::Time& stamp) {
    std::unique_lock<std::mutex> lock(mutex_);
    awaited_cloud_stamp_ = stamp;
    clouds_at_awaited_stamp_ = 0;
    awaited_cloud_.reset();
    changed_.wait_for(lock, std::chrono::duration<double>(kStatusTimeout_s),
                      [&] { return clouds_at_awaited_stamp_ >= 2; });
    return clouds_at_awaited_stamp_ >= 2 ? awaited_cloud_ : nullptr;
  }
  /// The cloud's points whose colour is within `levels` of `colour` in each channel (none when it
  /// has no rgb field).
  static bool hasRgb(const sensor_msgs::PointCloud2& cloud) {
    return std::any_of(cloud.fields.begin(), cloud.fields.end(),
                       [](const sensor_msgs::PointField& f) { return f.name == "rgb"; });
  }
  static size_t pointsOfColour(const sensor_msgs::PointCloud2& cloud, const st::Rgb& colour, int levels) {
    if (!hasRgb(cloud)) return 0;
    size_t n = 0;
    sensor_msgs::PointCloud2ConstIterator<uint8_t> r(cloud, "r"), g(cloud, "g"), b(cloud, "b");
    for (; r != r.end(); ++r, ++g, ++b) {
      n += std::abs(*r - colour[0]) <= levels && std::abs(*g - colour[1]) <= levels &&
           std::abs(*b - colour[2]) <= levels;
    }
    return n;
  }

  /// A width x height image of `encoding` whose every pixel is `pixel`'s bytes.
  static sensor_msgs::Image uniformImage(uint32_t width, uint32_t height, const std::string& encoding,
                                         const std::vector<uint8_t>& pixel) {
    sensor_msgs::Image image;
    image.width = width;
    image.height = height;
    image.encoding = encoding;
    image.step = width * static_cast<uint32_t>(pixel.size());
    image.data.resize(static_cast<size_t>(image.step) * height);
    for (size_t i = 0; i < image.data.size(); ++i) image.data[i] = pixel[i % pixel.size()];
    return image;
  }

  ros::Publisher colour_pub_;
  ros::Subscriber diagnostics_sub_, rosout_sub_, full_cloud_sub_;
  std::optional<diagnostic_msgs::DiagnosticStatus> colour_status_;
  std::vector<std::string> warnings_;
  ros::Time awaited_cloud_stamp_;
  int clouds_at_awaited_stamp_ = 0;
  sensor_msgs::PointCloud2ConstPtr awaited_cloud_;
};

// Colour images in an encoding the node cannot read (a depth camera's 16UC1, a driver's yuv422),
// and colour images of another size than the depth's, on the topic the node listens to: every
// frame is tracked and fused all the same, without their colour, and the node's warning and the
// "sdf_tracker: colour" diagnostics (WARN) name the encoding, or both sizes. Colour images it can
// use then colour the map: the refused ones reached the node and were refused, not missed.
TEST_F(NodeColourTest, ColourItCannotUseIsNamedAndTheDepthIsTrackedAndFusedWithout) {
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  const std::string topic = "/camera/rgb/image_color";
  const diagnostic_msgs::DiagnosticStatus before = colourStatus([](const auto&) { return true; });
  ASSERT_EQ(before.name, kColourTask) << "no \"" << kColourTask << "\" on /diagnostics";
  const int coloured_before = count(before, "frames fused in colour");
  const int uncoloured_before = count(before, "frames fused without colour");
  ASSERT_GE(coloured_before, 0) << "no \"frames fused in colour\" in \"" << kColourTask << "\"";
  ASSERT_GE(uncoloured_before, 0) << "no \"frames fused without colour\" in \"" << kColourTask << "\"";
  size_t poses_before;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    poses_before = poses_.size();
  }

  constexpr int kFramesEach = 3;
  const double first_stamp_s = 400.0;
  int frame = 0;
  ros::Time last_stamp;
  auto sendFrames = [&](const sensor_msgs::Image& colour, const std::string& label) {
    for (int i = 0; i < kFramesEach; ++i, ++frame) {
      const double t_s = frame / 30.0;
      last_stamp = ros::Time(first_stamp_s + t_s);
      const auto status = publishWithColour(colour, first_stamp_s + t_s, t_s);
      EXPECT_EQ(status.status, sdf_tracker::TrackingStatus::OK)
          << label << ", frame " << frame << ": " << status.status_text;
      EXPECT_TRUE(status.fused) << label << ", frame " << frame << ": " << status.status_text;
    }
  };
  // The colour image's problem, as "sdf_tracker: colour" states it at WARN.
  auto expectWarning = [&](const std::vector<std::string>& parts, const std::string& label) {
    const diagnostic_msgs::DiagnosticStatus status = colourStatus([&](const diagnostic_msgs::DiagnosticStatus& s) {
      return s.level == diagnostic_msgs::DiagnosticStatus::WARN &&
             std::all_of(parts.begin(), parts.end(),
                         [&](const std::string& p) { return s.message.find(p) != std::string::npos; });
    });
    EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::WARN) << label << ": \"" << status.message << "\"";
    for (const std::string& part : parts) {
      EXPECT_NE(status.message.find(part), std::string::npos)
          << label << ": \"" << status.message << "\" lacks " << part;
    }
  };

  // Bytes far from the cloud's grey, were they taken for colour (16UC1 and yuv422: two bytes a pixel).
  sendFrames(uniformImage(kQvga.width, kQvga.height, "16UC1", {0xFF, 0x00}), "16UC1");
  expectWarning({"unsupported colour encoding \"16UC1\""}, "16UC1");
  EXPECT_TRUE(warned({topic, "unsupported colour encoding \"16UC1\"", "fused without colour"}))
      << "no warning on /rosout naming the colour topic and the encoding 16UC1";

  sendFrames(uniformImage(kQvga.width, kQvga.height, "yuv422", {0x80, 0xFF}), "yuv422");
  expectWarning({"unsupported colour encoding \"yuv422\""}, "yuv422");
  // (Not asked on /rosout: the node's line for an unreadable colour image is throttled to one in 2 s.)

  sendFrames(uniformImage(2 * kQvga.width, 2 * kQvga.height, "rgb8", {255, 0, 0}), "VGA colour with QVGA depth");
  expectWarning({"640x480", "320x240"}, "VGA colour with QVGA depth");
  EXPECT_TRUE(warned({topic, "the colour image is 640x480, the depth image 320x240", "fused without colour"}))
      << "no warning on /rosout naming the colour topic and both sizes";

  const int refused = frame;
  const diagnostic_msgs::DiagnosticStatus after = colourStatus([&](const diagnostic_msgs::DiagnosticStatus& s) {
    return count(s, "frames fused without colour") >= uncoloured_before + refused;
  });
  EXPECT_EQ(count(after, "frames fused without colour"), uncoloured_before + refused) << after.message;
  EXPECT_EQ(count(after, "frames fused in colour"), coloured_before) << after.message;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_EQ(poses_.size(), poses_before + refused) << "every frame is tracked and goes out on ~pose";
    EXPECT_EQ(last_path_.poses.size(), static_cast<size_t>(refused)) << "the path holds every frame since the reset";
  }
  // The map holds no colour: every point of ~cloud is the grey of a surface never seen in colour.
  sensor_msgs::PointCloud2ConstPtr cloud = cloudAt(last_stamp);
  ASSERT_TRUE(cloud) << "no ~cloud stamped " << last_stamp;
  const size_t points = cloud->width * cloud->height;
  EXPECT_GT(points, 1000u);
  if (hasRgb(*cloud)) {
    EXPECT_EQ(pointsOfColour(*cloud, st::kUnseenColour, 0), points) << "points of ~cloud carry colour";
  }

  // Colour the node can use, 320x240 rgb8: the frames are fused in it, the warning is over, and
  // the map shows it.
  const st::Rgb green = {40, 200, 60};
  sendFrames(uniformImage(kQvga.width, kQvga.height, "rgb8", {green[0], green[1], green[2]}), "rgb8");
  const diagnostic_msgs::DiagnosticStatus good = colourStatus([&](const diagnostic_msgs::DiagnosticStatus& s) {
    return count(s, "frames fused in colour") >= coloured_before + kFramesEach;
  });
  EXPECT_EQ(count(good, "frames fused in colour"), coloured_before + kFramesEach) << good.message;
  EXPECT_EQ(good.level, diagnostic_msgs::DiagnosticStatus::OK) << good.message;
  cloud = cloudAt(last_stamp);
  ASSERT_TRUE(cloud) << "no ~cloud stamped " << last_stamp;
  const size_t green_points = pointsOfColour(*cloud, green, 2);
  std::cout << "[ figures  ] " << green_points << " of " << cloud->width * cloud->height
            << " points of ~cloud in the colour images' green\n";
  EXPECT_GT(green_points, cloud->width * cloud->height / 2)
      << "the colour images the node can use do not colour the map";
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));  // a map without colour again
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

  const std::string folder = st::test::scratchDirectory("output_check");
  const std::string trajectory = folder + "/trajectory.txt";
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
  const std::string dump = st::test::scratchDirectory("corrupt_calibration");
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
  const int result = RUN_ALL_TESTS();
  st::test::removeScratchDirectories(result == 0);
  return result;
}
