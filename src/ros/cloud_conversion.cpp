// The only translation unit that includes PCL (it is slow to compile).
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl_conversions/pcl_conversions.h>

#include "sdf_tracker/ros/conversions.h"

namespace sdf_tracker_ros {

sensor_msgs::PointCloud2 toCloudMsg(const sdf_tracker::SurfaceCloud& cloud, const std_msgs::Header& header) {
  pcl::PointCloud<pcl::PointNormal> points;
  points.reserve(cloud.points_W.size());
  for (size_t i = 0; i < cloud.points_W.size(); ++i) {
    pcl::PointNormal p;
    p.x = cloud.points_W[i].x();
    p.y = cloud.points_W[i].y();
    p.z = cloud.points_W[i].z();
    p.normal_x = cloud.normals_W[i].x();
    p.normal_y = cloud.normals_W[i].y();
    p.normal_z = cloud.normals_W[i].z();
    p.curvature = 0.0f;
    points.push_back(p);
  }
  sensor_msgs::PointCloud2 msg;
  pcl::toROSMsg(points, msg);
  msg.header = header;
  return msg;
}

}  // namespace sdf_tracker_ros
