// Drives the real sdf_tracker_node with a bag that tum_to_bag made from a synthetic QVGA sequence
// (image + its own camera_info), frame by frame in lock-step with the node's ~status; checks tf,
// path, cloud, accuracy against the offline pipeline on the same frames, bad input, the
// save_mesh service and rejected reconfiguration.

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <tuple>

#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Path.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <std_srvs/Empty.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include "sdf_tracker/SavePath.h"
#include "sdf_tracker/SaveRegion.h"
#include "sdf_tracker/TrackingStatus.h"
#include "sdf_tracker/core/evaluation.h"
#include "sdf_tracker/core/io.h"
#include "sdf_tracker/core/parameters.h"
#include "sdf_tracker/core/pipeline.h"
#include "sdf_tracker/core/synthetic.h"
#include "sdf_tracker/core/tum_sequence.h"
#include "sdf_tracker/ros/conversions.h"

namespace st = sdf_tracker;

namespace {

// The node and the offline pipeline see the same frames; they may differ only by float order.
constexpr double kMaxAteDifference_m = 0.01;
constexpr double kStatusTimeout_s = 20.0;
constexpr double kResend_s = 2.0;
/// The camera of every synthetic frame the tests send.
const st::PinholeCamera kQvga = st::PinholeCamera::tumFreiburg1().scaledTo(320, 240);

class NodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    image_pub_ = nh_.advertise<sensor_msgs::Image>("camera/depth/image", 5);
    info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("camera/depth/camera_info", 5);
    status_sub_ = nh_.subscribe("sdf_tracker/status", 50, &NodeTest::onStatus, this);
    pose_sub_ = nh_.subscribe("sdf_tracker/pose", 50, &NodeTest::onPose, this);
    path_sub_ = nh_.subscribe("sdf_tracker/path", 5, &NodeTest::onPath, this);
    cloud_sub_ = nh_.subscribe("sdf_tracker/cloud", 1, &NodeTest::onCloud, this);
    spinner_.start();
    ASSERT_TRUE(ros::service::waitForService("sdf_tracker/save_mesh", ros::Duration(60.0)));
    // Both directions: the node hears our frames, and we hear its status and pose.
    for (int i = 0; i < 100 && (image_pub_.getNumSubscribers() == 0 || info_pub_.getNumSubscribers() == 0 ||
                                status_sub_.getNumPublishers() == 0 || pose_sub_.getNumPublishers() == 0);
         ++i) {
      ros::Duration(0.1).sleep();
    }
  }

  void onStatus(const sdf_tracker::TrackingStatus& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    statuses_.push_back(msg);
    changed_.notify_all();
  }
  void onPose(const geometry_msgs::PoseStamped& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    poses_.push_back({msg.header.stamp.toSec(), sdf_tracker_ros::fromPoseMsg(msg.pose)});
  }
  void onPath(const nav_msgs::Path& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    path_length_ = msg.poses.size();
  }
  void onCloud(const sensor_msgs::PointCloud2& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    cloud_points_ = msg.width * msg.height;
  }

  /// Publishes one frame and waits for the node's status about it.
  sdf_tracker::TrackingStatus publishAndWait(const sensor_msgs::Image& image, const st::PinholeCamera& camera) {
    std::unique_lock<std::mutex> lock(mutex_);
    const size_t before = statuses_.size();
    const sensor_msgs::CameraInfo info = sdf_tracker_ros::toCameraInfo(camera, image.header);
    // Connections come up one by one (the node has several subscribers per topic): re-send the
    // pair until the node answers. A pair it already took is dropped by stamp, never tracked twice.
    bool arrived = false;
    for (double waited_s = 0.0; !arrived && waited_s < kStatusTimeout_s; waited_s += kResend_s) {
      lock.unlock();
      info_pub_.publish(info);
      image_pub_.publish(image);
      lock.lock();
      arrived = changed_.wait_for(lock, std::chrono::duration<double>(kResend_s),
                                  [&] { return statuses_.size() > before; });
    }
    EXPECT_TRUE(arrived) << "no status for the frame stamped " << image.header.stamp;
    return arrived ? statuses_.back() : sdf_tracker::TrackingStatus();
  }

  /// The room's exact depth from the desk path at t_s, as the QVGA camera's frame stamped stamp_s.
  static sensor_msgs::Image deskFrame(double stamp_s, double t_s,
                                      const std::string& frame_id = "camera_depth_optical_frame") {
    st::synthetic::NoiseModel exact;
    exact.enabled = false;
    std_msgs::Header header;
    header.stamp = ros::Time(stamp_s);
    header.frame_id = frame_id;
    const auto T = st::synthetic::cameraPose(st::synthetic::Motion::kDesk, t_s, 10.0);
    return sdf_tracker_ros::toImageMsg(st::synthetic::Scene::indoorRoom().render(kQvga, T, exact, 0), header);
  }
  /// Publishes deskFrame(stamp_s, t_s) and waits for the node's status about it.
  sdf_tracker::TrackingStatus publishDeskFrame(double stamp_s, double t_s) {
    return publishAndWait(deskFrame(stamp_s, t_s), kQvga);
  }

  ros::NodeHandle nh_;
  ros::AsyncSpinner spinner_{1};
  ros::Publisher image_pub_, info_pub_;
  ros::Subscriber status_sub_, pose_sub_, path_sub_, cloud_sub_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<sdf_tracker::TrackingStatus> statuses_;
  std::vector<st::io::StampedPose> poses_;
  size_t path_length_ = 0;
  size_t cloud_points_ = 0;
};

/// A QVGA synthetic sequence converted by the package's own tum_to_bag, as a user would.
std::string makeSyntheticBag(const std::string& directory, int frames) {
  st::synthetic::SequenceSpec spec;
  spec.frames = frames;
  spec.camera = kQvga;
  spec.seed = 11;
  st::synthetic::writeSequence(directory, spec);
  const std::string bag = directory + "/sequence.bag";
  const std::string command = "rosrun sdf_tracker tum_to_bag " + directory + " " + bag + " > /dev/null";
  if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  return bag;
}

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

TEST_F(NodeTest, SaveMeshWritesAPlyThatLoadsBack) {
  ASSERT_TRUE(ros::service::call("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  // Three frames of its own after a reset, whatever ran before.
  for (int i = 0; i < 3; ++i) publishDeskFrame(100.0 + i, 0.0);
  sdf_tracker::SavePath save;
  save.request.path = "/tmp/sdf_tracker_node_test_mesh.ply";
  ASSERT_TRUE(ros::service::call("sdf_tracker/save_mesh", save));
  EXPECT_TRUE(save.response.success) << save.response.message;
  const st::TriangleMesh mesh = st::io::readPlyMesh(save.request.path);
  EXPECT_GT(mesh.triangles.size(), 1000u);
}

TEST_F(NodeTest, AMapSavedBySaveVolumeIsTrackedInAfterLoadVolume) {
  ASSERT_TRUE(ros::service::call("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  for (int i = 0; i < 3; ++i) publishDeskFrame(500.0 + i / 30.0, i / 30.0);
  sdf_tracker::SavePath save;
  save.request.path = "/tmp/sdf_tracker_node_test_map.sdfmap";
  ASSERT_TRUE(ros::service::call("sdf_tracker/save_volume", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  EXPECT_GT(st::io::readSparseMap(save.request.path).blockCount(), 100u) << "the dense grid is saved as its blocks";

  ASSERT_TRUE(ros::service::call("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  sdf_tracker::SavePath load;
  load.request.path = save.request.path;
  ASSERT_TRUE(ros::service::call("sdf_tracker/load_volume", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  const auto in_loaded = publishDeskFrame(510.0, 1 / 30.0);
  EXPECT_EQ(in_loaded.status, sdf_tracker::TrackingStatus::OK) << in_loaded.status_text;
  EXPECT_EQ(in_loaded.status_text.find("first frame"), std::string::npos)
      << "the frame is tracked in the loaded map, not used to start a new one: " << in_loaded.status_text;

  load.request.path = "/tmp/sdf_tracker_node_test_missing.sdfmap";
  ASSERT_TRUE(ros::service::call("sdf_tracker/load_volume", load));
  EXPECT_FALSE(load.response.success);
  EXPECT_NE(load.response.message.find(load.request.path), std::string::npos) << load.response.message;
}

TEST_F(NodeTest, SaveVolumeRegionWritesTheBoxGivenInTheMapFrame) {
  ASSERT_TRUE(ros::service::call("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  for (int i = 0; i < 3; ++i) publishDeskFrame(600.0 + i / 30.0, i / 30.0);
  // In the map frame (REP 103: x forward, y left, z up from the first camera): 0.6 to 1.4 m ahead,
  // 0.3 m either side, 0.2 m below to 0.4 m above the camera.
  sdf_tracker::SaveRegion save;
  save.request.path = "/tmp/sdf_tracker_node_test_region.vti";
  save.request.min.x = 0.6, save.request.min.y = -0.3, save.request.min.z = -0.2;
  save.request.max.x = 1.4, save.request.max.y = 0.3, save.request.max.z = 0.4;
  ASSERT_TRUE(ros::service::call("sdf_tracker/save_volume_region", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  // The file is in the tracker's own axes (the first camera's optical frame: x right, y down,
  // z forward): the same box, within a voxel at each end.
  const st::TsdfVolume region = st::io::readVti(save.request.path);
  const st::VolumeConfig& c = region.config();
  const Eigen::Vector3d lo = c.origin_W, hi = c.origin_W + (c.dims - Eigen::Vector3i::Ones()).cast<double>() * c.voxel_size_m;
  const Eigen::Vector3d want_lo(-0.3, -0.4, 0.6), want_hi(0.3, 0.2, 1.4);
  EXPECT_LT((lo - want_lo).cwiseAbs().maxCoeff(), c.voxel_size_m + 1e-9) << lo.transpose();
  EXPECT_LT((hi - want_hi).cwiseAbs().maxCoeff(), c.voxel_size_m + 1e-9) << hi.transpose();
  EXPECT_NE(save.response.message.find(save.request.path), std::string::npos) << save.response.message;

  // A box inside out, and a file that is not a .vti: refused, saying what was given.
  std::swap(save.request.min.x, save.request.max.x);
  ASSERT_TRUE(ros::service::call("sdf_tracker/save_volume_region", save));
  EXPECT_FALSE(save.response.success);
  EXPECT_NE(save.response.message.find("min < max"), std::string::npos) << save.response.message;
  EXPECT_NE(save.response.message.find("1.4"), std::string::npos) << save.response.message;
  std::swap(save.request.min.x, save.request.max.x);
  save.request.path = "/tmp/sdf_tracker_node_test_region.ply";
  ASSERT_TRUE(ros::service::call("sdf_tracker/save_volume_region", save));
  EXPECT_FALSE(save.response.success);
  EXPECT_NE(save.response.message.find(save.request.path), std::string::npos) << save.response.message;
}

/// Collects ~mesh_blocks messages from its own subscription.
class MeshBlocksListener {
 public:
  explicit MeshBlocksListener(ros::NodeHandle& nh)
      : sub_(nh.subscribe("sdf_tracker/mesh_blocks", 10, &MeshBlocksListener::onArray, this)) {}
  /// The next message that arrives after this call (nullopt after `timeout_s`).
  std::optional<visualization_msgs::MarkerArray> next(double timeout_s = 10.0) {
    std::unique_lock<std::mutex> lock(mutex_);
    const size_t before = arrays_.size();
    if (!arrived_.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] { return arrays_.size() > before; })) {
      return std::nullopt;
    }
    return arrays_.back();
  }

 private:
  void onArray(const visualization_msgs::MarkerArray& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    arrays_.push_back(msg);
    arrived_.notify_all();
  }
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<visualization_msgs::MarkerArray> arrays_;
  ros::Subscriber sub_;
};

/// Markers that add triangles, and whether the array starts by clearing what was shown.
std::pair<size_t, bool> chunkMarkers(const visualization_msgs::MarkerArray& array) {
  size_t added = 0;
  for (const auto& marker : array.markers) added += marker.action == visualization_msgs::Marker::ADD;
  return {added, !array.markers.empty() && array.markers.front().action == visualization_msgs::Marker::DELETEALL};
}

TEST_F(NodeTest, MeshBlocksSendsANewViewerEverythingAndThenOnlyTheChunksThatChanged) {
  ASSERT_TRUE(ros::service::call("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  for (int i = 0; i < 3; ++i) publishDeskFrame(700.0 + i / 30.0, i / 30.0);
  MeshBlocksListener viewer(nh_);
  ASSERT_TRUE(viewer.next()) << "nothing on ~mesh_blocks";

  // The map as blocks (whichever storage it had, an earlier test may have loaded one): the
  // viewer is told to start over and gets every chunk.
  sdf_tracker::SavePath path;
  path.request.path = "/tmp/sdf_tracker_node_test_chunks.sdfmap";
  ASSERT_TRUE(ros::service::call("sdf_tracker/save_volume", path));
  ASSERT_TRUE(ros::service::call("sdf_tracker/load_volume", path));
  ASSERT_TRUE(path.response.success) << path.response.message;
  std::optional<visualization_msgs::MarkerArray> all;
  for (int tries = 0; tries < 3 && !(all && chunkMarkers(*all).second); ++tries) all = viewer.next();
  ASSERT_TRUE(all && chunkMarkers(*all).second) << "no array starting over after the load";
  const size_t all_chunks = chunkMarkers(*all).first;
  EXPECT_GT(all_chunks, 5u);

  // A frame that measures one quadrant of the image changes part of the map: only the chunks it
  // changed are sent.
  sensor_msgs::Image patch = deskFrame(710.0, 3 / 30.0);
  {
    st::DepthImage depth = sdf_tracker_ros::toDepthImage(patch);
    for (int v = 0; v < depth.height(); ++v) {
      for (int u = 0; u < depth.width(); ++u) {
        if (u > depth.width() / 2 || v < depth.height() / 2) depth.at(u, v) = 0.0f;
      }
    }
    patch = sdf_tracker_ros::toImageMsg(depth, patch.header);
  }
  const auto patch_status = publishAndWait(patch, kQvga);
  EXPECT_EQ(patch_status.status, sdf_tracker::TrackingStatus::OK) << patch_status.status_text;
  std::optional<visualization_msgs::MarkerArray> changed;
  for (int tries = 0; tries < 3 && !(changed && chunkMarkers(*changed).first > 0); ++tries) changed = viewer.next();
  ASSERT_TRUE(changed) << "no chunks sent after the patch was fused";
  EXPECT_FALSE(chunkMarkers(*changed).second) << "an update does not start over";
  EXPECT_GT(chunkMarkers(*changed).first, 0u);
  EXPECT_LT(chunkMarkers(*changed).first, all_chunks / 2);

  // A second viewer joins (another process: one process shares one connection per topic): it is
  // sent everything, and so, in the same message, is the first.
  ASSERT_EQ(std::system("timeout 20 rostopic echo -n 1 /sdf_tracker/mesh_blocks > /dev/null 2>&1 &"), 0);
  std::optional<visualization_msgs::MarkerArray> joined;
  for (int tries = 0; tries < 5 && !(joined && chunkMarkers(*joined).second); ++tries) joined = viewer.next();
  ASSERT_TRUE(joined && chunkMarkers(*joined).second) << "no array starting over for the new viewer";
  EXPECT_GE(chunkMarkers(*joined).first, all_chunks);
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

/// Sends one parameter through dynamic_reconfigure; returns the values the node reports in force.
std::map<std::string, st::ParameterValue> reconfigure(const std::string& name, const st::ParameterValue& value) {
  dynamic_reconfigure::Reconfigure srv;
  if (const auto* d = std::get_if<double>(&value)) {
    dynamic_reconfigure::DoubleParameter p;
    p.name = name, p.value = *d;
    srv.request.config.doubles.push_back(p);
  } else if (const auto* i = std::get_if<int>(&value)) {
    dynamic_reconfigure::IntParameter p;
    p.name = name, p.value = *i;
    srv.request.config.ints.push_back(p);
  } else if (const auto* b = std::get_if<bool>(&value)) {
    dynamic_reconfigure::BoolParameter p;
    p.name = name, p.value = *b;
    srv.request.config.bools.push_back(p);
  } else {
    dynamic_reconfigure::StrParameter p;
    p.name = name, p.value = std::get<std::string>(value);
    srv.request.config.strs.push_back(p);
  }
  std::map<std::string, st::ParameterValue> in_force;
  if (!ros::service::call("sdf_tracker/set_parameters", srv)) {
    ADD_FAILURE() << "set_parameters failed";
    return in_force;
  }
  for (const auto& p : srv.response.config.doubles) in_force[p.name] = p.value;
  for (const auto& p : srv.response.config.ints) in_force[p.name] = static_cast<int>(p.value);
  for (const auto& p : srv.response.config.bools) in_force[p.name] = static_cast<bool>(p.value);
  for (const auto& p : srv.response.config.strs) in_force[p.name] = p.value;
  return in_force;
}

/// A value other than `current` that the table accepts and that keeps `settings` valid.
std::optional<st::ParameterValue> anotherValidValue(const st::ParameterSpec& spec, const st::Settings& settings) {
  std::vector<st::ParameterValue> candidates;
  const st::ParameterValue current = spec.get(settings);
  if (const auto* b = std::get_if<bool>(&current)) candidates = {!*b};
  if (const auto* i = std::get_if<int>(&current)) candidates = {*i + 1, *i - 1};
  if (const auto* d = std::get_if<double>(&current)) candidates = {*d * 1.1, *d * 0.9, *d + 0.01, *d - 0.01};
  if (spec.name == "TrackingSchedule") candidates = {std::string("4x10,2x5,1x1")};
  for (const auto& choice : spec.choices) candidates.push_back(choice);
  for (const auto& candidate : candidates) {
    if (candidate == current) continue;
    st::Settings trial = settings;
    try {
      st::setParameter(&trial, spec.name, candidate);
    } catch (const std::invalid_argument&) {
      continue;
    }
    if (trial.validate().empty()) return candidate;
  }
  return std::nullopt;
}

TEST_F(NodeTest, EveryLiveParameterIsReconfigurableAndEveryOutOfRangeValueIsRefused) {
  // The node runs the default preset with a 160^3 grid (node.test).
  st::Settings expected = st::preset("default");
  expected.pipeline.volume.dims = Eigen::Vector3i(160, 160, 160);
  int live = 0;
  for (const st::ParameterSpec& spec : st::parameterTable()) {
    if (!spec.live) continue;
    ++live;
    SCOPED_TRACE(spec.name);
    const st::ParameterValue before = spec.get(expected);
    if (spec.range) {  // beyond the range: refused, never clamped
      const double outside = std::isfinite(spec.range->high) && spec.range->high < 1e8 ? spec.range->high * 2 + 1
                                                                                     : spec.range->low - 1;
      const st::ParameterValue bad = spec.type == st::ParameterType::kInt ? st::ParameterValue(static_cast<int>(outside))
                                                                         : st::ParameterValue(outside);
      EXPECT_EQ(reconfigure(spec.name, bad)[spec.name], before) << "out-of-range value " << st::toText(bad);
    }
    if (spec.type == st::ParameterType::kText) {
      EXPECT_EQ(reconfigure(spec.name, std::string("not a value"))[spec.name], before);
    }
    const std::optional<st::ParameterValue> valid = anotherValidValue(spec, expected);
    ASSERT_TRUE(valid.has_value()) << "no valid alternative found to try";
    EXPECT_EQ(reconfigure(spec.name, *valid)[spec.name], *valid) << "valid value " << st::toText(*valid);
    st::setParameter(&expected, spec.name, *valid);
  }
  EXPECT_GT(live, 10);
  // A refused change reports what is in force in the pipeline: every accepted value is there.
  const auto in_force = reconfigure("MaxWeight", -5.0);
  for (const st::ParameterSpec& spec : st::parameterTable()) {
    if (spec.live) {
      EXPECT_EQ(in_force.at(spec.name), spec.get(expected)) << spec.name;
    }
  }
}

/// Runs a command through the shell; returns its exit code and what it printed.
std::pair<int, std::string> runCommand(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  std::string output;
  char buffer[4096];
  while (pipe && fgets(buffer, sizeof(buffer), pipe)) output += buffer;
  const int status = pipe ? pclose(pipe) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

// The tracker refuses to start on a TUM camera it does not know, or on two sources of intrinsics,
// and says which parameter and value; nothing is guessed.
TEST(TrackerNode, RefusesAnUnknownTumCameraAndTwoSourcesOfIntrinsicsByName) {
  const std::string node = "timeout 30 rosrun sdf_tracker sdf_tracker_node __name:=tum_camera_check ";
  auto [code, output] = runCommand(node + "_tum_camera:=freiburg4");
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("~tum_camera must be one of freiburg1, freiburg2, freiburg3, or empty for camera_info's "
                        "calibration (got \"freiburg4\")"),
            std::string::npos)
      << output;
  std::tie(code, output) = runCommand(node + "_tum_camera:=freiburg1 _FocalLengthX:=500.0");
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("~tum_camera (freiburg1) and FocalLength/CenterPoint both give the intrinsics"),
            std::string::npos)
      << output;
}

// The camera drivers on a machine without a camera, or pointed at a recording that is not there:
// an error that names what is missing, and a non-zero exit (roslaunch then ends the launch).
TEST(CameraDrivers, WithoutACameraOrRecordingExitWithAnErrorNamingIt) {
  const std::string driver = "ROS_NAMESPACE=no_camera timeout 30 rosrun sdf_tracker ";
  auto [code, output] = runCommand(driver + "openni2_depth_publisher");
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("no OpenNI 2 camera found"), std::string::npos) << output;

  std::tie(code, output) = runCommand(driver + "openni2_depth_publisher _device_id:=/nonexistent/recording.oni");
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("cannot open ~device_id \"/nonexistent/recording.oni\""), std::string::npos) << output;

  std::tie(code, output) = runCommand(driver + "openni2_depth_publisher _depth_mode:=HD");
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("~depth_mode must be VGA or QVGA (got \"HD\")"), std::string::npos) << output;

  std::tie(code, output) = runCommand(driver + "kinect_depth_publisher");
  EXPECT_EQ(code, 1) << output;
  EXPECT_TRUE(output.find("no Kinect found") != std::string::npos ||
              output.find("libfreenect failed to initialise") != std::string::npos)
      << output;

  // Through libfreenect's own replay wrapper, as kinect.launch fakenect:= runs it.
  std::tie(code, output) = runCommand("ROS_NAMESPACE=no_camera timeout 30 fakenect /nonexistent/dump rosrun sdf_tracker kinect_depth_publisher");
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("FAKENECT_PATH=/nonexistent/dump: cannot open /nonexistent/dump/INDEX.txt"), std::string::npos)
      << output;
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sdf_tracker_node_test");
  return RUN_ALL_TESTS();
}
