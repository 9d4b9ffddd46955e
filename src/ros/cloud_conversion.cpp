// The only translation unit that includes PCL (it is slow to compile).
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl_conversions/pcl_conversions.h>

#include "sdf_tracker/ros/conversions.h"

namespace sdf_tracker_ros {

sensor_msgs::PointCloud2 toCloudMsg(const sdf_tracker::SurfaceCloud& cloud, const std_msgs::Header& header,
                                    const Eigen::Isometry3d& T_frame_W) {
  const Eigen::Isometry3f T = T_frame_W.cast<float>();
  pcl::PointCloud<pcl::PointNormal> points;
  points.reserve(cloud.points_W.size());
  for (size_t i = 0; i < cloud.points_W.size(); ++i) {
    pcl::PointNormal p;
    const Eigen::Vector3f point = T * cloud.points_W[i];
    const Eigen::Vector3f normal = T.linear() * cloud.normals_W[i];
    p.x = point.x();
    p.y = point.y();
    p.z = point.z();
    p.normal_x = normal.x();
    p.normal_y = normal.y();
    p.normal_z = normal.z();
    p.curvature = 0.0f;
    points.push_back(p);
  }
  sensor_msgs::PointCloud2 msg;
  pcl::toROSMsg(points, msg);
  msg.header = header;
  return msg;
}

}  // namespace sdf_tracker_ros
