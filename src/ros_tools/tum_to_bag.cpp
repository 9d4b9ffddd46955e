// tum_to_bag: converts a TUM-layout folder into a rosbag shaped like the TUM RGB-D benchmark's own
// bags of 2011, so the ROS workflow can be tried and tested exactly as with a downloaded bag.
//   rosrun sdf_tracker tum_to_bag SEQUENCE_DIR OUT.bag [--frames N] [--openni-default-intrinsics]
//                                 [--without-odometry]
// As in the benchmark's bags:
//   /camera/depth/image (32FC1 metres, NaN = no data) + /camera/depth/camera_info,
//   frame "/openni_depth_optical_frame" (with its leading slash);
//   /tf as the legacy tf/tfMessage: the ground truth /world -> /kinect at its own rate (when the
//   folder has groundtruth.txt), and the rigid openni chain /kinect -> /openni_camera ->
//   /openni_depth_frame -> /openni_depth_optical_frame (and its openni_rgb_* twin) at 30 Hz;
//   nothing on /tf_static;
//   /camera/rgb/image_color (rgb8) + /camera/rgb/camera_info when the folder has rgb.txt, and
//   /imu when it has accelerometer.txt ("timestamp ax ay az", m/s^2, in the depth camera's frame);
//   and, beyond the benchmark, a robot's wheel odometry when it has odometry.txt (the camera's poses
//   in the odometry's frame, as sdf_tracker_synth --odometry writes them): /odom -> /base_link on
//   /tf at each of its poses, the base being the camera's mount (/base_link -> /kinect, identity,
//   with the chain), as a robot's odometry publishes it. With --without-odometry the mount is
//   there but /odom -> /base_link is not: a robot whose odometry is down.
// camera_info holds the sequence's intrinsics; with --openni-default-intrinsics it holds what the
// benchmark's own bags are expected to hold instead (inferred from the driver, not checked on one):
// the OpenNI driver's default (fx = fy = 525, the image centre, D all zero), which is not the
// camera's calibration (the node's ~tum_camera gives that).
// The bag is written to a temporary file and renamed when complete: a failure leaves no bag.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include <geometry_msgs/TransformStamped.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/image_encodings.h>
#include <tf/tfMessage.h>

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/devices/recording.h"
#include "sdf_tracker/io/colour_image_file.h"
#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/io/tum_sequence.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/ros/conversions.h"

namespace {

namespace st = sdf_tracker;

constexpr const char* kUsage =
    "usage: tum_to_bag SEQUENCE_DIR OUT.bag [--frames N] [--openni-default-intrinsics] [--without-odometry]";
constexpr double kChainRate_hz = 30.0;  ///< as the openni driver re-published its static frames

/// A link of the openni chain: parent, child, transform parent <- child.
struct Link {
  std::string parent;
  std::string child;
  Eigen::Isometry3d T_parent_child;
};

Eigen::Isometry3d translation(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

/// Body frame (x forward, y left, z up) <- optical frame (x right, y down, z forward).
Eigen::Isometry3d bodyFromOptical() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return T;
}

/// The openni driver's frames, as in the benchmark's bags: depth and colour cameras 2.5 cm apart.
std::vector<Link> openniChain() {
  return {{"/kinect", "/openni_camera", Eigen::Isometry3d::Identity()},
          {"/openni_camera", "/openni_depth_frame", translation(0.0, -0.02, 0.0)},
          {"/openni_depth_frame", "/openni_depth_optical_frame", bodyFromOptical()},
          {"/openni_camera", "/openni_rgb_frame", translation(0.0, -0.045, 0.0)},
          {"/openni_rgb_frame", "/openni_rgb_optical_frame", bodyFromOptical()}};
}

/// The camera's mount on a robot whose odometry the bag carries: its base is the mount itself.
Link robotMount() { return {"/base_link", "/kinect", Eigen::Isometry3d::Identity()}; }

/// /kinect <- /openni_depth_optical_frame through the chain.
Eigen::Isometry3d kinectFromDepthOptical(const std::vector<Link>& chain) {
  return chain[0].T_parent_child * chain[1].T_parent_child * chain[2].T_parent_child;
}

geometry_msgs::TransformStamped toTransform(const Eigen::Isometry3d& T, const ros::Time& stamp,
                                            const std::string& parent, const std::string& child) {
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = stamp;
  tf.header.frame_id = parent;
  tf.child_frame_id = child;
  const geometry_msgs::Pose pose = sdf_tracker_ros::toPoseMsg(T);
  tf.transform.translation.x = pose.position.x;
  tf.transform.translation.y = pose.position.y;
  tf.transform.translation.z = pose.position.z;
  tf.transform.rotation = pose.orientation;
  return tf;
}

/// A TUM list's lines (rgb.txt, accelerometer.txt), or none when the folder has no such file.
std::vector<st::TimedLine> readOptionalList(const std::string& path) {
  return std::ifstream(path) ? st::readTimedList(path) : std::vector<st::TimedLine>();
}

/// About how many bytes the bag of `sequence` takes: its depth images as 32-bit floats and its
/// colour images as 8-bit RGB, which is nearly all of it.
uint64_t estimatedBagBytes(const st::TumSequence& sequence, size_t colour_images) {
  const uint64_t pixels = static_cast<uint64_t>(sequence.camera().width) * sequence.camera().height;
  return sequence.size() * pixels * 4 + colour_images * pixels * 3;
}

int run(int argc, char** argv) {
  const st::tools::CommandLine args(argc, argv, {"frames"}, {"help", "openni-default-intrinsics", "without-odometry"},
                                    {"SEQUENCE_DIR", "OUT.bag"});
  if (args.has("help")) {
    std::cout << kUsage << "\n";
    return 0;
  }
  const st::TumSequence sequence = st::tools::openSequence(args);
  const std::string out = args.positional(1);
  const std::string temporary = out + ".partial";

  const double offset_s = st::devices::rosStampOffset(sequence);
  const double t_end = sequence.timestamp(sequence.size() - 1);
  std::vector<Link> chain = openniChain();
  const Eigen::Isometry3d T_depth_kinect = kinectFromDepthOptical(chain).inverse();
  const std::string odometry_path = args.positional(0) + "/odometry.txt";
  std::vector<st::io::StampedPose> odometry =
      std::ifstream(odometry_path) ? st::io::readTrajectory(odometry_path) : std::vector<st::io::StampedPose>{};
  if (!odometry.empty()) chain.push_back(robotMount());
  if (args.has("without-odometry")) {
    if (odometry.empty()) throw std::invalid_argument("--without-odometry: " + odometry_path + " holds no odometry to leave out");
    odometry.clear();
  }
  const auto& gt = sequence.groundTruth();
  const auto colour = readOptionalList(args.positional(0) + "/rgb.txt");
  const auto accelerometer = readOptionalList(args.positional(0) + "/accelerometer.txt");
  // What camera_info says about an image of the given size.
  auto recordedCamera = [&](int width, int height) {
    if (args.has("openni-default-intrinsics")) return st::PinholeCamera::openNiDefault(width, height);
    st::PinholeCamera camera = sequence.camera();
    camera.width = width, camera.height = height;
    return camera;
  };

  st::io::requireFreeSpace(out, estimatedBagBytes(sequence, colour.size()), "the bag");
  // On a failed write the bag is let go without destroying it: its destructor would write its
  // index to the same full disk and throw again, which ends the process.
  auto bag_owner = std::make_unique<rosbag::Bag>();
  rosbag::Bag& bag = *bag_owner;
  try {
    bag.open(temporary, rosbag::bagmode::Write);
    auto stamp = [offset_s](double t) { return ros::Time(t + offset_s); };
    // Every stream in time order up to each depth frame, so playback interleaves them as recorded.
    size_t gt_index = 0, colour_index = 0, accel_index = 0, odometry_index = 0;
    double next_chain_s = std::min(sequence.timestamp(0), gt.empty() ? sequence.timestamp(0) : gt.front().timestamp_s);
    auto writeUpTo = [&](double until_s) {
      while (gt_index < gt.size() && gt[gt_index].timestamp_s <= until_s) {
        tf::tfMessage tf;
        const ros::Time t = stamp(gt[gt_index].timestamp_s);
        tf.transforms.push_back(toTransform(gt[gt_index].T_W_C * T_depth_kinect, t, "/world", "/kinect"));
        bag.write("/tf", t, tf);
        ++gt_index;
      }
      while (odometry_index < odometry.size() && odometry[odometry_index].timestamp_s <= until_s) {
        tf::tfMessage tf;
        const ros::Time t = stamp(odometry[odometry_index].timestamp_s);
        tf.transforms.push_back(
            toTransform(odometry[odometry_index].T_W_C * T_depth_kinect, t, "/odom", robotMount().parent));
        bag.write("/tf", t, tf);
        ++odometry_index;
      }
      while (next_chain_s <= until_s) {
        tf::tfMessage tf;
        const ros::Time t = stamp(next_chain_s);
        for (const Link& link : chain) tf.transforms.push_back(toTransform(link.T_parent_child, t, link.parent, link.child));
        bag.write("/tf", t, tf);
        next_chain_s += 1.0 / kChainRate_hz;
      }
      while (accel_index < accelerometer.size() && accelerometer[accel_index].timestamp_s <= until_s) {
        std::istringstream fields(accelerometer[accel_index].rest);
        sensor_msgs::Imu imu;
        imu.header.stamp = stamp(accelerometer[accel_index].timestamp_s);
        imu.header.frame_id = "/openni_depth_optical_frame";
        imu.orientation_covariance[0] = -1.0;  // no orientation
        imu.angular_velocity_covariance[0] = -1.0;
        if (!(fields >> imu.linear_acceleration.x >> imu.linear_acceleration.y >> imu.linear_acceleration.z)) {
          throw std::runtime_error(args.positional(0) + "/accelerometer.txt: expected \"timestamp ax ay az\"");
        }
        bag.write("/imu", imu.header.stamp, imu);
        ++accel_index;
      }
      while (colour_index < colour.size() && colour[colour_index].timestamp_s <= until_s) {
        std_msgs::Header header;
        header.seq = static_cast<uint32_t>(colour_index);
        header.stamp = stamp(colour[colour_index].timestamp_s);
        header.frame_id = "/openni_rgb_optical_frame";
        const std::string path = args.positional(0) + "/" + colour[colour_index].firstWord();
        const sensor_msgs::Image image = sdf_tracker_ros::toImageMsg(st::io::readColourImage(path), header);
        const st::PinholeCamera camera = recordedCamera(static_cast<int>(image.width), static_cast<int>(image.height));
        bag.write("/camera/rgb/image_color", header.stamp, image);
        bag.write("/camera/rgb/camera_info", header.stamp, sdf_tracker_ros::toCameraInfo(camera, header));
        ++colour_index;
      }
    };
    for (size_t i = 0; i < sequence.size(); ++i) {
      writeUpTo(sequence.timestamp(i));
      std_msgs::Header header;
      header.seq = static_cast<uint32_t>(i);
      header.stamp = stamp(sequence.timestamp(i));
      header.frame_id = "/openni_depth_optical_frame";
      bag.write("/camera/depth/image", header.stamp, sdf_tracker_ros::toImageMsg(sequence.depth(i), header));
      const st::PinholeCamera camera = recordedCamera(sequence.camera().width, sequence.camera().height);
      bag.write("/camera/depth/camera_info", header.stamp, sdf_tracker_ros::toCameraInfo(camera, header));
    }
    writeUpTo(t_end + 0.1);  // the ground truth and chain just past the last frame
    bag.close();
  } catch (const std::exception& e) {
    bag_owner.release();
    std::remove(temporary.c_str());
    throw std::runtime_error(out + ": writing the bag failed (" + e.what() + "); nothing was left behind");
  }
  if (std::rename(temporary.c_str(), out.c_str()) != 0) {
    std::remove(temporary.c_str());
    throw std::runtime_error("cannot move the finished bag to " + out);
  }
  std::cout << "wrote " << sequence.size() << " frames";
  if (!odometry.empty()) std::cout << " and " << odometry.size() << " wheel odometry poses (/odom -> /base_link)";
  std::cout << " to " << out;
  if (offset_s != 0.0) std::cout << " (stamps shifted by " << offset_s << " s)";
  std::cout << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return sdf_tracker::tools::runTool("tum_to_bag", run, argc, argv); }
