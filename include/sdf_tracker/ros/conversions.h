#pragma once

#include <string>

#include <geometry_msgs/Pose.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <visualization_msgs/Marker.h>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/colour_image.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/surface/surface.h"

/// Conversions between ROS messages and core types, in one place (REP 118 depth: 16UC1
/// millimetres or 32FC1 metres, 0 or NaN = no measurement).
namespace sdf_tracker_ros {

/// Converts a depth image to metres. Throws std::invalid_argument naming the encoding or the
/// inconsistency (step, size) when the image cannot be read.
sdf_tracker::DepthImage toDepthImage(const sensor_msgs::Image& msg);

/// A 32FC1 image in metres (NaN where there is no measurement).
sensor_msgs::Image toImageMsg(const sdf_tracker::DepthImage& depth, const std_msgs::Header& header);

/// Converts a colour image (rgb8, bgr8, rgba8, bgra8 or mono8) to RGB. Throws
/// std::invalid_argument naming the encoding or the inconsistency (step, size).
sdf_tracker::ColourImage toColourImage(const sensor_msgs::Image& msg);
/// An rgb8 image.
sensor_msgs::Image toImageMsg(const sdf_tracker::ColourImage& colour, const std_msgs::Header& header);

/// Intrinsics (K) and lens distortion (D, plumb_bob or rational_polynomial without k4..k6) from
/// camera_info; throws std::invalid_argument for a zero or non-finite K or size, or a distortion
/// the pipeline cannot remove.
sdf_tracker::PinholeCamera toCamera(const sensor_msgs::CameraInfo& info);
/// The inverse: camera_info (plumb_bob) of the camera.
sensor_msgs::CameraInfo toCameraInfo(const sdf_tracker::PinholeCamera& camera, const std_msgs::Header& header);

/// The TUM RGB-D camera ~tum_camera names (PinholeCamera::tumCamera); throws std::invalid_argument
/// naming the parameter, the value and the cameras there are for any other name.
sdf_tracker::PinholeCamera tumCameraNamed(const std::string& tum_camera);

/// camera_info holds what the OpenNI driver sends when it knows no calibration (as in the TUM RGB-D
/// benchmark's bags): PinholeCamera::openNiDefault for its size, D all zero.
bool holdsOpenNiDefault(const sensor_msgs::CameraInfo& info);

/// The camera a depth image with this camera_info (from `info_topic`) is tracked with, and in
/// `source` where it came from, for the log. `tum_camera` (~tum_camera) names a TUM RGB-D camera
/// whose published calibration replaces camera_info's K and D; empty: camera_info as it is, D all
/// zero meaning no distortion (when K is a TUM camera's, `source` says so and names ~tum_camera).
/// Throws std::invalid_argument naming ~tum_camera when that camera does not take images of the
/// info's size, and as toCamera does.
sdf_tracker::PinholeCamera trackingCamera(const sensor_msgs::CameraInfo& info, const std::string& info_topic,
                                          const std::string& tum_camera, std::string* source);

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& T);
Eigen::Isometry3d fromPoseMsg(const geometry_msgs::Pose& pose);

/// A triangle-list marker of the mesh, in its vertex colours when it has them (else one grey);
/// `T_frame_W` places the tracker's world in header.frame_id.
visualization_msgs::Marker toMarker(const sdf_tracker::TriangleMesh& mesh, const std_msgs::Header& header,
                                    const Eigen::Isometry3d& T_frame_W = Eigen::Isometry3d::Identity());

}  // namespace sdf_tracker_ros

#include <sensor_msgs/PointCloud2.h>

namespace sdf_tracker_ros {
/// Surface points with normals as PointCloud2 (x y z normal_x normal_y normal_z, and rgb, as rviz's
/// RGB8 colour transformer reads it, when the cloud has colours or `rgb_field` asks for one: then
/// kUnseenColour for a cloud without, even an empty one, so that rviz keeps its RGB8 transformer,
/// which it gives up at the first cloud without the field), built with PCL.
/// Implemented in its own translation unit so that only one file compiles PCL.
/// `T_frame_W` places the tracker's world in header.frame_id (points and normals are transformed).
sensor_msgs::PointCloud2 toCloudMsg(const sdf_tracker::SurfaceCloud& cloud, const std_msgs::Header& header,
                                    const Eigen::Isometry3d& T_frame_W = Eigen::Isometry3d::Identity(),
                                    bool rgb_field = false);
}  // namespace sdf_tracker_ros
