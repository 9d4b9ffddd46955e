#include "sdf_tracker/ros/conversions.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>

#include <sensor_msgs/distortion_models.h>
#include <sensor_msgs/image_encodings.h>

namespace sdf_tracker_ros {

namespace enc = sensor_msgs::image_encodings;

namespace {

/// An image message of this size and encoding, rows packed, its data allocated.
sensor_msgs::Image imageMsg(const std_msgs::Header& header, int width, int height, const std::string& encoding,
                            uint32_t bytes_per_pixel) {
  sensor_msgs::Image msg;
  msg.header = header;
  msg.width = static_cast<uint32_t>(width);
  msg.height = static_cast<uint32_t>(height);
  msg.encoding = encoding;
  msg.is_bigendian = 0;
  msg.step = msg.width * bytes_per_pixel;
  msg.data.resize(static_cast<size_t>(msg.step) * msg.height);
  return msg;
}

}  // namespace

sdf_tracker::DepthImage toDepthImage(const sensor_msgs::Image& msg) {
  const bool millimetres = msg.encoding == enc::TYPE_16UC1 || msg.encoding == enc::MONO16;
  const bool metres = msg.encoding == enc::TYPE_32FC1;
  if (!millimetres && !metres) {
    throw std::invalid_argument("unsupported depth encoding \"" + msg.encoding +
                                "\" (expected 16UC1 millimetres or 32FC1 metres)");
  }
  const size_t pixel_bytes = millimetres ? 2 : 4;
  if (msg.width == 0 || msg.height == 0 || msg.step < msg.width * pixel_bytes ||
      msg.data.size() < static_cast<size_t>(msg.step) * msg.height) {
    throw std::invalid_argument("inconsistent image: " + std::to_string(msg.width) + "x" + std::to_string(msg.height) +
                                ", step " + std::to_string(msg.step) + ", " + std::to_string(msg.data.size()) +
                                " bytes");
  }
  if (msg.is_bigendian) throw std::invalid_argument("big-endian depth images are not supported");
  sdf_tracker::DepthImage depth(static_cast<int>(msg.width), static_cast<int>(msg.height));
  for (uint32_t v = 0; v < msg.height; ++v) {
    const uint8_t* row = msg.data.data() + static_cast<size_t>(v) * msg.step;
    if (metres) {  // already float metres: one copy per row
      std::memcpy(&depth.at(0, static_cast<int>(v)), row, static_cast<size_t>(msg.width) * 4);
      continue;
    }
    for (uint32_t u = 0; u < msg.width; ++u) {
      uint16_t raw;
      std::memcpy(&raw, row + u * 2, 2);
      depth.at(static_cast<int>(u), static_cast<int>(v)) = raw == 0 ? 0.0f : raw * 0.001f;
    }
  }
  return depth;
}

sensor_msgs::Image toImageMsg(const sdf_tracker::DepthImage& depth, const std_msgs::Header& header) {
  sensor_msgs::Image msg = imageMsg(header, depth.width(), depth.height(), enc::TYPE_32FC1, 4);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < depth.height(); ++v) {
    for (int u = 0; u < depth.width(); ++u) {
      const float z = sdf_tracker::DepthImage::isMeasurement(depth.at(u, v)) ? depth.at(u, v) : nan;
      std::memcpy(msg.data.data() + (static_cast<size_t>(v) * depth.width() + u) * 4, &z, 4);
    }
  }
  return msg;
}

sdf_tracker::ColourImage toColourImage(const sensor_msgs::Image& msg) {
  // Where red, green and blue sit in a pixel, and its bytes.
  struct Layout {
    const char* encoding;
    int bytes, r, g, b;
  };
  static const Layout kLayouts[] = {{"rgb8", 3, 0, 1, 2}, {"bgr8", 3, 2, 1, 0}, {"rgba8", 4, 0, 1, 2},
                                    {"bgra8", 4, 2, 1, 0}, {"mono8", 1, 0, 0, 0}};
  const Layout* layout = nullptr;
  for (const Layout& l : kLayouts) {
    if (msg.encoding == l.encoding) layout = &l;
  }
  if (!layout) {
    throw std::invalid_argument("unsupported colour encoding \"" + msg.encoding +
                                "\" (expected rgb8, bgr8, rgba8, bgra8 or mono8)");
  }
  if (msg.width == 0 || msg.height == 0 || msg.step < msg.width * static_cast<uint32_t>(layout->bytes) ||
      msg.data.size() < static_cast<size_t>(msg.step) * msg.height) {
    throw std::invalid_argument("inconsistent colour image: " + std::to_string(msg.width) + "x" +
                                std::to_string(msg.height) + " " + msg.encoding + ", step " + std::to_string(msg.step) +
                                ", " + std::to_string(msg.data.size()) + " bytes");
  }
  sdf_tracker::ColourImage colour(static_cast<int>(msg.width), static_cast<int>(msg.height));
  for (uint32_t v = 0; v < msg.height; ++v) {
    const uint8_t* in = msg.data.data() + static_cast<size_t>(v) * msg.step;
    uint8_t* out = colour.at(0, static_cast<int>(v));
    if (layout->bytes == 3 && layout->r == 0) {
      std::memcpy(out, in, static_cast<size_t>(msg.width) * 3);
      continue;
    }
    for (uint32_t u = 0; u < msg.width; ++u, in += layout->bytes, out += 3) {
      out[0] = in[layout->r], out[1] = in[layout->g], out[2] = in[layout->b];
    }
  }
  return colour;
}

sensor_msgs::Image toImageMsg(const sdf_tracker::ColourImage& colour, const std_msgs::Header& header) {
  sensor_msgs::Image msg = imageMsg(header, colour.width(), colour.height(), enc::RGB8, 3);
  std::copy(colour.data(), colour.data() + msg.data.size(), msg.data.begin());
  return msg;
}

sdf_tracker::PinholeCamera toCamera(const sensor_msgs::CameraInfo& info) {
  sdf_tracker::PinholeCamera camera;
  camera.fx = info.K[0];
  camera.fy = info.K[4];
  camera.cx = info.K[2];
  camera.cy = info.K[5];
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  // plumb_bob's five coefficients; rational_polynomial's are the same five, then k4 k5 k6.
  const bool plumb_bob = info.distortion_model == sensor_msgs::distortion_models::PLUMB_BOB;
  const bool rational = info.distortion_model == sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL;
  const bool any_distortion = std::any_of(info.D.begin(), info.D.end(), [](double d) { return d != 0.0; });
  if (any_distortion) {
    const size_t expected = plumb_bob ? 5 : 8;
    if (!plumb_bob && !rational) {
      throw std::invalid_argument("camera_info: distortion_model \"" + info.distortion_model +
                                  "\" is not supported (plumb_bob or rational_polynomial)");
    }
    if (info.D.size() != expected) {
      throw std::invalid_argument("camera_info: " + info.distortion_model + " needs " + std::to_string(expected) +
                                  " coefficients in D, got " + std::to_string(info.D.size()));
    }
    if (rational && (info.D[5] != 0.0 || info.D[6] != 0.0 || info.D[7] != 0.0)) {
      throw std::invalid_argument("camera_info: rational_polynomial with k4..k6 (D[5..7]) not zero is not supported");
    }
    camera.distortion = {info.D[0], info.D[1], info.D[2], info.D[3], info.D[4]};
  }
  const auto violations = camera.validate();
  if (!violations.empty()) throw std::invalid_argument("camera_info: " + violations.front());
  return camera;
}

sdf_tracker::PinholeCamera tumCameraNamed(const std::string& tum_camera) {
  const std::optional<sdf_tracker::PinholeCamera> camera = sdf_tracker::PinholeCamera::tumCamera(tum_camera);
  if (!camera) {
    throw std::invalid_argument("tum_camera must be one of " + sdf_tracker::PinholeCamera::tumCameraNames() +
                                ", or empty for camera_info's calibration (got \"" + tum_camera + "\")");
  }
  return *camera;
}

bool holdsOpenNiDefault(const sensor_msgs::CameraInfo& info) {
  const auto guess =
      sdf_tracker::PinholeCamera::openNiDefault(static_cast<int>(info.width), static_cast<int>(info.height));
  const bool no_distortion = std::all_of(info.D.begin(), info.D.end(), [](double d) { return d == 0.0; });
  return no_distortion && info.K[0] == guess.fx && info.K[4] == guess.fy && info.K[2] == guess.cx &&
         info.K[5] == guess.cy && info.K[1] == 0.0;
}

sdf_tracker::PinholeCamera trackingCamera(const sensor_msgs::CameraInfo& info, const std::string& info_topic,
                                          const std::string& tum_camera, std::string* source) {
  if (!tum_camera.empty()) {
    const sdf_tracker::PinholeCamera camera = tumCameraNamed(tum_camera);
    if (const std::string mismatch = camera.sizeMismatch(info.width, info.height); !mismatch.empty()) {
      throw std::invalid_argument("~tum_camera " + tum_camera + ": " + mismatch);
    }
    *source = "~tum_camera " + tum_camera + ", TUM's published calibration";
    return camera;
  }
  sdf_tracker::PinholeCamera camera = toCamera(info);
  *source = info_topic;
  // D all zero states "no distortion", as image_geometry reads it. Intrinsics that match a TUM
  // camera's are said, never acted on.
  if (camera.distortion.isZero()) {
    if (const std::string tum = sdf_tracker::PinholeCamera::tumCameraWithIntrinsicsOf(camera); !tum.empty()) {
      *source += " with D all zero; these are TUM " + tum + "'s intrinsics: if the images are TUM's, set ~tum_camera:=" +
                 tum + " for its published calibration";
    }
  }
  return camera;
}

sensor_msgs::CameraInfo toCameraInfo(const sdf_tracker::PinholeCamera& c, const std_msgs::Header& header) {
  sensor_msgs::CameraInfo info;
  info.header = header;
  info.width = static_cast<uint32_t>(c.width);
  info.height = static_cast<uint32_t>(c.height);
  info.distortion_model = sensor_msgs::distortion_models::PLUMB_BOB;
  const sdf_tracker::LensDistortion& d = c.distortion;
  info.D = {d.k1, d.k2, d.p1, d.p2, d.k3};
  info.K = {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {c.fx, 0, c.cx, 0, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  return info;
}

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose pose;
  const Eigen::Quaterniond q(T.linear());
  pose.position.x = T.translation().x();
  pose.position.y = T.translation().y();
  pose.position.z = T.translation().z();
  pose.orientation.x = q.x();
  pose.orientation.y = q.y();
  pose.orientation.z = q.z();
  pose.orientation.w = q.w();
  return pose;
}

Eigen::Isometry3d fromPoseMsg(const geometry_msgs::Pose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  T.linear() = Eigen::Quaterniond(pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z)
                   .normalized()
                   .toRotationMatrix();
  return T;
}

visualization_msgs::Marker toMarker(const sdf_tracker::TriangleMesh& mesh, const std_msgs::Header& header,
                                    const Eigen::Isometry3d& T_frame_W) {
  visualization_msgs::Marker marker;
  marker.header = header;
  marker.ns = "sdf_tracker";
  marker.id = 0;
  marker.type = visualization_msgs::Marker::TRIANGLE_LIST;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose = toPoseMsg(T_frame_W);  // rviz applies it to every vertex
  marker.scale.x = marker.scale.y = marker.scale.z = 1.0;
  marker.color.r = 0.75f;
  marker.color.g = 0.75f;
  marker.color.b = 0.8f;
  marker.color.a = 1.0f;
  const bool coloured = !mesh.colours.empty();
  marker.points.reserve(mesh.triangles.size() * 3);
  if (coloured) marker.colors.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles) {
    for (int m = 0; m < 3; ++m) {
      geometry_msgs::Point p;
      p.x = mesh.vertices_W[t[m]].x();
      p.y = mesh.vertices_W[t[m]].y();
      p.z = mesh.vertices_W[t[m]].z();
      marker.points.push_back(p);
      if (coloured) {
        // rviz takes a triangle list's colours per point, in place of marker.color.
        const sdf_tracker::Rgb& c = mesh.colours[t[m]];
        std_msgs::ColorRGBA colour;
        colour.r = c[0] / 255.0f, colour.g = c[1] / 255.0f, colour.b = c[2] / 255.0f, colour.a = 1.0f;
        marker.colors.push_back(colour);
      }
    }
  }
  return marker;
}

}  // namespace sdf_tracker_ros
