// The only translation unit that includes PCL (it is slow to compile).
#include <type_traits>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl_conversions/pcl_conversions.h>

#include "sdf_tracker/ros/conversions.h"

namespace sdf_tracker_ros {

sensor_msgs::PointCloud2 toCloudMsg(const sdf_tracker::SurfaceCloud& cloud, const std_msgs::Header& header,
                                    const Eigen::Isometry3d& T_frame_W, bool rgb_field) {
  const Eigen::Isometry3f T = T_frame_W.cast<float>();
  // PointNormal, or PointXYZRGBNormal when the cloud has colours: the same points either way.
  const auto fill = [&](auto& points, auto&& colour) {
    points.reserve(cloud.points_W.size());
    for (size_t i = 0; i < cloud.points_W.size(); ++i) {
      typename std::decay_t<decltype(points)>::PointType p;
      const Eigen::Vector3f point = T * cloud.points_W[i];
      const Eigen::Vector3f normal = T.linear() * cloud.normals_W[i];
      p.x = point.x();
      p.y = point.y();
      p.z = point.z();
      p.normal_x = normal.x();
      p.normal_y = normal.y();
      p.normal_z = normal.z();
      p.curvature = 0.0f;
      colour(i, &p);
      points.push_back(p);
    }
    sensor_msgs::PointCloud2 msg;
    pcl::toROSMsg(points, msg);
    msg.header = header;
    return msg;
  };
  const bool coloured = !cloud.colours.empty();
  if (!coloured && !rgb_field) {
    pcl::PointCloud<pcl::PointNormal> points;
    return fill(points, [](size_t, pcl::PointNormal*) {});
  }
  pcl::PointCloud<pcl::PointXYZRGBNormal> points;
  return fill(points, [&cloud, coloured](size_t i, pcl::PointXYZRGBNormal* p) {
    const sdf_tracker::Rgb& c = coloured ? cloud.colours[i] : sdf_tracker::kUnseenColour;
    p->r = c[0];
    p->g = c[1];
    p->b = c[2];
    p->a = 255;
  });
}

}  // namespace sdf_tracker_ros
