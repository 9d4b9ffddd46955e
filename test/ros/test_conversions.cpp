#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <set>

#include <cmath>
#include <cstring>

#include <sensor_msgs/image_encodings.h>

#include "sdf_tracker/SdfTrackerConfig.h"
#include "sdf_tracker/map/block_swap.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/ros/map_publisher.h"
#include "sdf_tracker/ros/odometry.h"
#include "sdf_tracker/ros/parameters.h"
#include "sdf_tracker/ros/pose_broadcaster.h"

namespace sdf_tracker_ros {
namespace {

sensor_msgs::Image millimetreImage(uint32_t width, uint32_t height, uint16_t value) {
  sensor_msgs::Image msg;
  msg.width = width;
  msg.height = height;
  msg.encoding = sensor_msgs::image_encodings::TYPE_16UC1;
  msg.step = width * 2;
  msg.data.resize(msg.step * height);
  for (size_t i = 0; i < static_cast<size_t>(width) * height; ++i) std::memcpy(&msg.data[2 * i], &value, 2);
  return msg;
}

TEST(Conversions, MillimetresAndMetresGiveTheSameDepth) {
  const sdf_tracker::DepthImage mm = toDepthImage(millimetreImage(4, 3, 1234));
  EXPECT_FLOAT_EQ(mm.at(3, 2), 1.234f);
  std_msgs::Header header;
  header.frame_id = "cam";
  const sensor_msgs::Image metres = toImageMsg(mm, header);
  EXPECT_EQ(metres.encoding, sensor_msgs::image_encodings::TYPE_32FC1);
  EXPECT_EQ(metres.header.frame_id, "cam");
  EXPECT_FLOAT_EQ(toDepthImage(metres).at(1, 1), 1.234f);
}

TEST(Conversions, ZeroAndNaNAreNoMeasurement) {
  const sdf_tracker::DepthImage zero = toDepthImage(millimetreImage(2, 2, 0));
  EXPECT_EQ(zero.countMeasurements(), 0);
  sdf_tracker::DepthImage nan(2, 2, std::nanf(""));
  EXPECT_EQ(toDepthImage(toImageMsg(nan, std_msgs::Header())).countMeasurements(), 0);
}

TEST(Conversions, UnreadableImagesNameTheProblem) {
  sensor_msgs::Image colour = millimetreImage(4, 3, 1);
  colour.encoding = "rgb8";
  try {
    toDepthImage(colour);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rgb8"), std::string::npos);
  }
  sensor_msgs::Image short_data = millimetreImage(4, 3, 1);
  short_data.data.resize(5);
  EXPECT_THROW(toDepthImage(short_data), std::invalid_argument);
  sensor_msgs::CameraInfo info;
  info.width = 640;
  info.height = 480;  // K all zero: an uncalibrated camera
  EXPECT_THROW(toCamera(info), std::invalid_argument);
  info.K = {525, 0, 319.5, 0, 525, 239.5, 0, 0, 1};
  EXPECT_DOUBLE_EQ(toCamera(info).cx, 319.5);
}

TEST(Conversions, ColourImagesOfEveryEncodingAreReadAsRgbAndOthersAreRefusedByName) {
  // One pixel of red 10, green 20, blue 30 in each encoding (grey: 20).
  const std::map<std::string, std::vector<uint8_t>> pixels = {
      {"rgb8", {10, 20, 30}}, {"bgr8", {30, 20, 10}}, {"rgba8", {10, 20, 30, 255}}, {"bgra8", {30, 20, 10, 255}},
      {"mono8", {20}}};
  for (const auto& [encoding, pixel] : pixels) {
    sensor_msgs::Image msg;
    msg.width = 3;
    msg.height = 2;
    msg.encoding = encoding;
    msg.step = static_cast<uint32_t>(3 * pixel.size() + 2);  // rows padded
    msg.data.assign(msg.step * msg.height, 0);
    for (int v = 0; v < 2; ++v)
      for (int u = 0; u < 3; ++u) std::copy(pixel.begin(), pixel.end(), &msg.data[v * msg.step + u * pixel.size()]);
    const sdf_tracker::ColourImage colour = toColourImage(msg);
    ASSERT_EQ(colour.width(), 3);
    const uint8_t* c = colour.at(2, 1);
    if (encoding == "mono8") {
      EXPECT_EQ(std::vector<uint8_t>(c, c + 3), (std::vector<uint8_t>{20, 20, 20})) << encoding;
    } else {
      EXPECT_EQ(std::vector<uint8_t>(c, c + 3), (std::vector<uint8_t>{10, 20, 30})) << encoding;
    }
  }
  sensor_msgs::Image msg = toImageMsg(sdf_tracker::ColourImage(4, 2, 7), std_msgs::Header());
  EXPECT_EQ(msg.encoding, "rgb8");
  EXPECT_EQ(toColourImage(msg).at(3, 1)[2], 7) << "rgb8 round trip";
  msg.encoding = "16UC1";
  try {
    toColourImage(msg);
    FAIL() << "a 16UC1 image was taken for colour";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unsupported colour encoding \"16UC1\""), std::string::npos) << e.what();
  }
  msg.encoding = "rgb8";
  msg.data.resize(10);
  EXPECT_THROW(toColourImage(msg), std::invalid_argument) << "fewer bytes than its size";
}

TEST(Conversions, CloudAndMeshCarryTheirColoursToRviz) {
  sdf_tracker::SurfaceCloud cloud;
  cloud.points_W = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(4, 5, 6)};
  cloud.normals_W = {Eigen::Vector3f::UnitZ(), Eigen::Vector3f::UnitX()};
  const sensor_msgs::PointCloud2 grey = toCloudMsg(cloud, std_msgs::Header());
  EXPECT_TRUE(std::none_of(grey.fields.begin(), grey.fields.end(), [](const auto& f) { return f.name == "rgb"; }));
  // Asked for, an rgb field even without colours, even without points: rviz keeps its RGB8.
  const sensor_msgs::PointCloud2 empty = toCloudMsg(sdf_tracker::SurfaceCloud(), std_msgs::Header(),
                                                    Eigen::Isometry3d::Identity(), true);
  EXPECT_TRUE(std::any_of(empty.fields.begin(), empty.fields.end(), [](const auto& f) { return f.name == "rgb"; }));
  cloud.colours = {{200, 10, 20}, {1, 2, 3}};
  const sensor_msgs::PointCloud2 coloured = toCloudMsg(cloud, std_msgs::Header());
  const auto rgb = std::find_if(coloured.fields.begin(), coloured.fields.end(), [](const auto& f) { return f.name == "rgb"; });
  ASSERT_NE(rgb, coloured.fields.end()) << "rviz's RGB8 transformer reads the rgb field";
  // PCL packs rgb as b, g, r, a bytes (little-endian 0xAARRGGBB).
  const uint8_t* first = &coloured.data[rgb->offset];
  EXPECT_EQ(std::vector<uint8_t>(first, first + 3), (std::vector<uint8_t>{20, 10, 200}));
  EXPECT_EQ(coloured.width * coloured.height, 2u);

  sdf_tracker::TriangleMesh mesh;
  mesh.vertices_W = {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(0, 1, 0)};
  mesh.normals_W.assign(3, Eigen::Vector3f::UnitZ());
  mesh.triangles = {Eigen::Vector3i(0, 1, 2)};
  EXPECT_TRUE(toMarker(mesh, std_msgs::Header()).colors.empty()) << "no colours: the marker's one grey";
  mesh.colours = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
  const visualization_msgs::Marker marker = toMarker(mesh, std_msgs::Header());
  ASSERT_EQ(marker.colors.size(), 3u) << "one colour per point of the triangle list";
  EXPECT_FLOAT_EQ(marker.colors[1].g, 1.0f);
  EXPECT_FLOAT_EQ(marker.colors[2].b, 1.0f);
  EXPECT_FLOAT_EQ(marker.colors[2].a, 1.0f);
}

TEST(Conversions, CameraInfoRoundTripsThroughTheCamera) {
  sdf_tracker::PinholeCamera camera = sdf_tracker::PinholeCamera::tumFreiburg1();
  camera.distortion = {0.1, -0.2, 0.001, -0.002, 0.3};
  std_msgs::Header header;
  header.frame_id = "camera_depth_optical_frame";
  const sensor_msgs::CameraInfo info = toCameraInfo(camera, header);
  EXPECT_EQ(info.header.frame_id, "camera_depth_optical_frame");
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  EXPECT_EQ(info.P[2], camera.cx);
  const sdf_tracker::PinholeCamera back = toCamera(info);
  EXPECT_EQ(back.width, camera.width);
  EXPECT_EQ(back.height, camera.height);
  EXPECT_DOUBLE_EQ(back.fx, camera.fx);
  EXPECT_DOUBLE_EQ(back.fy, camera.fy);
  EXPECT_DOUBLE_EQ(back.cx, camera.cx);
  EXPECT_DOUBLE_EQ(back.cy, camera.cy);
  EXPECT_EQ(back.distortion, camera.distortion);
}

TEST(Conversions, ATumCameraReplacesTheBagsDriverDefaultCameraInfo) {
  // What the benchmark's bags of 2011 carry: the OpenNI driver's default.
  std_msgs::Header header;
  header.stamp = ros::Time(1305031102.16);
  const sensor_msgs::CameraInfo recorded = toCameraInfo(sdf_tracker::PinholeCamera::openNiDefault(640, 480), header);
  EXPECT_TRUE(holdsOpenNiDefault(recorded));
  std::string source;

  const sdf_tracker::PinholeCamera as_recorded =
      trackingCamera(recorded, "/camera/depth/camera_info", "", &source);
  EXPECT_EQ(as_recorded, sdf_tracker::PinholeCamera::openNiDefault(640, 480)) << "no TUM camera: camera_info as it is";
  EXPECT_EQ(source, "/camera/depth/camera_info");

  const sdf_tracker::PinholeCamera freiburg1 =
      trackingCamera(recorded, "/camera/depth/camera_info", "freiburg1", &source);
  EXPECT_EQ(freiburg1, *sdf_tracker::PinholeCamera::tumCamera("freiburg1")) << "intrinsics and distortion";
  EXPECT_FALSE(freiburg1.distortion.isZero());
  EXPECT_NE(source.find("~tum_camera freiburg1"), std::string::npos) << source;

  // camera_info that states TUM's freiburg1 intrinsics and D all zero states no distortion: the
  // match is said, with the parameter that would apply TUM's, and nothing is changed.
  const sensor_msgs::CameraInfo stated = toCameraInfo(sdf_tracker::PinholeCamera::tumFreiburg1(), header);
  EXPECT_FALSE(holdsOpenNiDefault(stated));
  EXPECT_EQ(trackingCamera(stated, "/camera/depth/camera_info", "", &source), sdf_tracker::PinholeCamera::tumFreiburg1());
  EXPECT_EQ(source, "/camera/depth/camera_info with D all zero; these are TUM freiburg1's intrinsics: if the images "
                    "are TUM's, set ~tum_camera:=freiburg1 for its published calibration");

  auto refusal = [&](const sensor_msgs::CameraInfo& info, const std::string& tum_camera) -> std::string {
    try {
      trackingCamera(info, "/camera/depth/camera_info", tum_camera, &source);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "accepted";
  };
  const sensor_msgs::CameraInfo qvga = toCameraInfo(sdf_tracker::PinholeCamera::openNiDefault(320, 240), header);
  EXPECT_TRUE(holdsOpenNiDefault(qvga));
  EXPECT_EQ(refusal(qvga, "freiburg1"), "~tum_camera freiburg1: depth image is 320x240 but the camera is 640x480");
  EXPECT_EQ(refusal(recorded, "freiburg4"),
            "tum_camera must be one of freiburg1, freiburg2, freiburg3, or empty for camera_info's calibration "
            "(got \"freiburg4\")");
}

TEST(Conversions, CameraInfoDistortionThePipelineCannotRemoveIsRefusedByName) {
  sensor_msgs::CameraInfo info = toCameraInfo(sdf_tracker::PinholeCamera(), std_msgs::Header());
  info.distortion_model = "rational_polynomial";
  info.D = {0.1, -0.2, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0};
  EXPECT_DOUBLE_EQ(toCamera(info).distortion.k3, 0.3) << "rational_polynomial without k4..k6 is plumb bob";
  info.D[6] = 0.01;
  auto refusal = [&]() -> std::string {
    try {
      toCamera(info);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(refusal().find("k4..k6"), std::string::npos) << refusal();
  info.distortion_model = "equidistant";
  info.D = {0.1, 0.0, 0.0, 0.0};
  EXPECT_NE(refusal().find("\"equidistant\""), std::string::npos) << refusal();
  info.D = {0.0, 0.0, 0.0, 0.0};
  EXPECT_TRUE(toCamera(info).distortion.isZero()) << "any model with zero coefficients is no distortion";
  info.distortion_model = "plumb_bob";
  info.D = {0.1, 0.2};
  EXPECT_NE(refusal().find("needs 5"), std::string::npos) << refusal();
  info.D.clear();
  EXPECT_TRUE(toCamera(info).distortion.isZero()) << "no D at all";
}

TEST(Reconfigure, TheCfgListsExactlyTheLiveRowsOfTheTableWithTheirTypesAndDefaultsAndNoClampingRange) {
  namespace st = sdf_tracker;
  const st::Settings defaults = st::preset("default");
  const sdf_tracker::SdfTrackerConfig cfg_defaults = sdf_tracker::SdfTrackerConfig::__getDefault__();
  const sdf_tracker::SdfTrackerConfig cfg_min = sdf_tracker::SdfTrackerConfig::__getMin__();
  const sdf_tracker::SdfTrackerConfig cfg_max = sdf_tracker::SdfTrackerConfig::__getMax__();
  std::map<std::string, st::ParameterValue> cfg_default_values;
  for (const auto& [name, value] : reconfigureValues(cfg_defaults)) cfg_default_values[name] = value;
  std::map<std::string, st::ParameterValue> cfg_min_values, cfg_max_values;
  for (const auto& [name, value] : reconfigureValues(cfg_min)) cfg_min_values[name] = value;
  for (const auto& [name, value] : reconfigureValues(cfg_max)) cfg_max_values[name] = value;

  std::set<std::string> in_cfg;
  for (const auto& description : sdf_tracker::SdfTrackerConfig::__getParamDescriptions__()) {
    in_cfg.insert(description->name);
    const st::ParameterSpec* spec = st::findParameter(description->name);
    ASSERT_NE(spec, nullptr) << description->name << " is in cfg/SdfTracker.cfg but not in the parameter table";
    EXPECT_TRUE(spec->live) << description->name << " is reconfigurable but its table row says it is not live";
    const std::string expected_type = spec->type == st::ParameterType::kText ? "str" : st::toString(spec->type);
    EXPECT_EQ(description->type, expected_type) << description->name;
    EXPECT_EQ(cfg_default_values.at(description->name), spec->defaults.of(st::Preset::kDefault))
        << description->name << ": the cfg default differs from the table's default preset";
    EXPECT_EQ(cfg_default_values.at(description->name), spec->get(defaults)) << description->name;
    // dynamic_reconfigure clamps to min/max silently: the cfg must not bound what the table checks.
    if (spec->type == st::ParameterType::kDouble) {
      EXPECT_EQ(std::get<double>(cfg_min_values.at(description->name)), -std::numeric_limits<double>::infinity())
          << description->name;
      EXPECT_EQ(std::get<double>(cfg_max_values.at(description->name)), std::numeric_limits<double>::infinity())
          << description->name;
    } else if (spec->type == st::ParameterType::kInt) {
      EXPECT_EQ(std::get<int>(cfg_min_values.at(description->name)), std::numeric_limits<int>::min()) << description->name;
      EXPECT_EQ(std::get<int>(cfg_max_values.at(description->name)), std::numeric_limits<int>::max()) << description->name;
    }
  }
  for (const st::ParameterSpec& spec : st::parameterTable()) {
    EXPECT_EQ(in_cfg.count(spec.name) > 0, spec.live) << spec.name << (spec.live ? " is live but missing from the cfg"
                                                                                    : " is in the cfg but not live");
  }
}

TEST(Reconfigure, ValuesRoundTripAtFullPrecision) {
  namespace st = sdf_tracker;
  st::Settings settings = st::preset("default");
  st::setParameter(&settings, "MaxWeight", 12345.678901234);
  st::setParameter(&settings, "ConvergenceCondition", 1.234567891e-7);
  st::Settings back = st::preset("default");
  for (const auto& [name, value] : reconfigureValues(toReconfigureConfig(settings))) st::setParameter(&back, name, value);
  EXPECT_EQ(back.pipeline.integrator.max_weight, 12345.678901234);
  EXPECT_EQ(back.pipeline.tracker.convergence_threshold, 1.234567891e-7);
}

TEST(Frames, TheMapFrameHasRep103AxesAtTheFirstCameraPose) {
  const Eigen::Isometry3d T_map_W = mapFromOpticalWorld();
  // The camera looks along optical +z: that is map +x (forward); optical +x (right) is map -y;
  // optical +y (down) is map -z.
  EXPECT_TRUE((T_map_W.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE((T_map_W.linear() * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitY()));
  EXPECT_TRUE((T_map_W.linear() * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(T_map_W.linear().determinant(), 1.0, 1e-12);
  // Gravity straight down the image (a level camera): the same frame.
  EXPECT_TRUE(gravityAlignedMapFromOpticalWorld(-Eigen::Vector3d::UnitY()).isApprox(T_map_W));
}

TEST(Frames, GravityLevelsTheMapFrameAndKeepsTheViewingDirectionForward) {
  // A camera pitched 30 degrees down: in its optical frame "up" leans towards -z.
  const double pitch = 30.0 * M_PI / 180.0;
  const Eigen::Vector3d up_W(0.0, -std::cos(pitch), -std::sin(pitch));
  const Eigen::Isometry3d T_map_W = gravityAlignedMapFromOpticalWorld(up_W * 9.81);
  EXPECT_TRUE((T_map_W.linear() * up_W).isApprox(Eigen::Vector3d::UnitZ())) << "map z is up";
  const Eigen::Vector3d forward = T_map_W.linear() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(forward.y(), 0.0, 1e-12) << "no yaw";
  EXPECT_GT(forward.x(), 0.0);
  EXPECT_NEAR(std::atan2(-forward.z(), forward.x()), pitch, 1e-9) << "the camera looks 30 degrees down";
  EXPECT_NEAR(T_map_W.linear().determinant(), 1.0, 1e-12);
  EXPECT_THROW(gravityAlignedMapFromOpticalWorld(Eigen::Vector3d::Zero()), std::invalid_argument);
  EXPECT_THROW(gravityAlignedMapFromOpticalWorld(Eigen::Vector3d(1e300, 1e300, 0.0)), std::invalid_argument)
      << "a length that overflows";
}

TEST(Frames, OnlyReadingsThatGravityDominatesCanLevelTheMapFrame) {
  EXPECT_TRUE(isGravityReading(Eigen::Vector3d(0.3, -9.7, 1.1)));
  EXPECT_TRUE(isGravityReading(Eigen::Vector3d(0.0, 0.0, 2.5 * 9.81))) << "a camera swung hard is still usable";
  EXPECT_FALSE(isGravityReading(Eigen::Vector3d::Zero())) << "a driver's placeholder";
  EXPECT_FALSE(isGravityReading(Eigen::Vector3d(1e300, 1e300, 0.0)));
  EXPECT_FALSE(isGravityReading(Eigen::Vector3d(std::nan(""), 9.81, 0.0)));
  EXPECT_FALSE(isGravityReading(Eigen::Vector3d(0.0, 0.0, std::numeric_limits<double>::infinity())));
}

TEST(Frames, APlanarPoseRequestSetsPositionAndHeadingAndKeepsHeightAndTilt) {
  auto rotation = [](double yaw, double pitch, double roll) {
    return Eigen::Matrix3d(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                           Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
  };
  auto heading = [](const Eigen::Isometry3d& T, const Eigen::Vector3d& axis) {
    const Eigen::Vector3d a = T.linear() * axis;
    return std::atan2(a.y(), a.x());
  };
  // A base leaning 15 degrees forward and 10 to the side, 0.8 m up, heading 30 degrees.
  Eigen::Isometry3d T_map_base = Eigen::Isometry3d::Identity();
  T_map_base.linear() = rotation(0.5236, -0.2618, 0.1745);
  T_map_base.translation() = Eigen::Vector3d(-3.0, 4.0, 0.8);
  const double yaw = -1.0472;
  const Eigen::Isometry3d placed =
      placedOnPlane(T_map_base, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), 1.0, 2.0, yaw);
  EXPECT_TRUE(placed.translation().isApprox(Eigen::Vector3d(1.0, 2.0, 0.8))) << placed.translation().transpose();
  EXPECT_NEAR(heading(placed, Eigen::Vector3d::UnitX()), yaw, 1e-9);
  // Only turned about the vertical: tilt (where the body's axes point up or down) is kept.
  const Eigen::Matrix3d turn = placed.linear() * T_map_base.linear().transpose();
  EXPECT_TRUE((turn * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(placed.linear()(2, axis), T_map_base.linear()(2, axis), 1e-12) << "axis " << axis;
  }

  // A camera heads along its optical z; looking straight down, along its image-up axis (-y).
  Eigen::Isometry3d T_map_C = mapFromOpticalWorld();
  const Eigen::Isometry3d camera = placedOnPlane(T_map_C, Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitY(), 0.0,
                                                 0.0, 0.5 * M_PI);
  EXPECT_TRUE((camera.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitY())) << "looks along map y";
  T_map_C.linear() = rotation(0.0, 0.5 * M_PI, 0.0) * mapFromOpticalWorld().linear();  // looking down
  const Eigen::Isometry3d down = placedOnPlane(T_map_C, Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitY(), 0.0,
                                               0.0, M_PI);
  EXPECT_TRUE((down.linear() * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitZ())) << "still looks down";
  EXPECT_TRUE((down.linear() * -Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitX()))
      << "its image top points at the heading";
}

TEST(Odometry, TheTrackersCovarianceBecomesTheBodysInRosOrderAlongTheMapAxes) {
  // The tracker's order is [rotation; translation]; ROS's is translation first.
  Covariance6d camera = Covariance6d::Zero();
  camera.diagonal() << 1e-4, 2e-4, 3e-4, 4e-6, 5e-6, 6e-6;
  const Covariance6d same_place = bodyPoseCovariance(camera, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  Eigen::Matrix<double, 6, 1> expected;
  expected << 4e-6, 5e-6, 6e-6, 1e-4, 2e-4, 3e-4;
  EXPECT_TRUE(same_place.diagonal().isApprox(expected)) << same_place.diagonal().transpose();
  // A base 1 m ahead of the camera along map x: turning about z moves it sideways (y).
  const Covariance6d ahead = bodyPoseCovariance(camera, Eigen::Matrix3d::Identity(), Eigen::Vector3d::UnitX());
  EXPECT_NEAR(ahead(1, 1), 5e-6 + 3e-4, 1e-12);
  EXPECT_NEAR(ahead(0, 0), 4e-6, 1e-12) << "not along the lever";
  EXPECT_NEAR(ahead(1, 5), 3e-4, 1e-12) << "sideways motion and yaw go together";
  // The world's axes turned into the map's: optical z (forward) is map x.
  const Covariance6d in_map = bodyPoseCovariance(camera, mapFromOpticalWorld().linear(), Eigen::Vector3d::Zero());
  EXPECT_NEAR(in_map(0, 0), 6e-6, 1e-15) << "map x is the optical z";
  EXPECT_NEAR(in_map(5, 5), 2e-4, 1e-15) << "yaw is about the optical -y";
}

TEST(Odometry, ACovarianceInASubmapsFrameTurnsWithTheFrameThePoseGraphGivesIt) {
  // [rotation; translation], each along the submap's axes; the graph turned it 90 degrees about z.
  Covariance6d camera = Covariance6d::Zero();
  camera.diagonal() << 1e-4, 2e-4, 3e-4, 4e-6, 5e-6, 6e-6;
  camera(3, 4) = camera(4, 3) = 1e-6;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Covariance6d turned = rotatedCovariance(camera, R);
  Eigen::Matrix<double, 6, 1> expected;
  expected << 2e-4, 1e-4, 3e-4, 5e-6, 4e-6, 6e-6;  // x and y swap places in both blocks
  EXPECT_TRUE(turned.diagonal().isApprox(expected)) << turned.diagonal().transpose();
  EXPECT_NEAR(turned(3, 4), -1e-6, 1e-15) << "x'y' = -yx";
  EXPECT_TRUE(rotatedCovariance(camera, Eigen::Matrix3d::Identity()).isApprox(camera));
}

TEST(Odometry, TwistFromSuccessivePosesAndAHeldPoseGrowsItsCovariance) {
  OdometryBuilder builder("map");
  Covariance6d tracked = 1e-6 * Covariance6d::Identity();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();  // heading map y
  const nav_msgs::Odometry first = builder.build(10.0, "base_link", T, tracked);
  EXPECT_EQ(first.header.frame_id, "map");
  EXPECT_EQ(first.child_frame_id, "base_link");
  EXPECT_DOUBLE_EQ(first.pose.covariance[0], 1e-6);
  EXPECT_GE(first.twist.covariance[0], 1e5) << "no motion is known from one pose";

  T.translation() = Eigen::Vector3d(0.05, 0.0, 0.0);  // 5 cm along map x in 0.1 s: to the body's right
  const nav_msgs::Odometry second = builder.build(10.1, "base_link", T, tracked);
  EXPECT_NEAR(second.twist.twist.linear.x, 0.0, 1e-9);
  EXPECT_NEAR(second.twist.twist.linear.y, -0.5, 1e-9) << "the twist is in the child frame";
  EXPECT_NEAR(second.twist.covariance[7], 2e-6 / 0.01, 1e-9) << "two poses' variance over dt^2";

  // Tracking failed for half a second: the held pose's covariance grows, never stays small.
  const nav_msgs::Odometry held = builder.build(10.6, "base_link", T, std::nullopt);
  EXPECT_NEAR(held.pose.covariance[0], std::pow(1e-3 + 0.5 * kHeldSpeed_mps, 2), 1e-9);
  EXPECT_NEAR(held.pose.covariance[35], std::pow(1e-3 + 0.5 * kHeldTurnRate_radps, 2), 1e-9);
  EXPECT_GE(held.twist.covariance[0], 1e5);

  // Issue 44: frames missing for 2 s (blank depth is dropped, no message goes out), then tracked
  // again: the motion over the gap says nothing of the velocity now (it was 2e-6, smaller than a
  // normal frame's).
  OdometryBuilder gap_builder("map");
  gap_builder.build(20.0, "base_link", T, tracked);
  const nav_msgs::Odometry after_gap = gap_builder.build(22.0, "base_link", T, tracked);
  EXPECT_GE(after_gap.twist.covariance[0], 1e5);
  EXPECT_GE(after_gap.twist.covariance[35], 1e5);
  const nav_msgs::Odometry next = gap_builder.build(22.0 + kMaxTwistInterval_s, "base_link", T, tracked);
  EXPECT_NEAR(next.twist.covariance[7], 2e-6 / std::pow(kMaxTwistInterval_s, 2), 1e-9) << "within the interval";
}

TEST(Frames, PosesRoundTripThroughMessages) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.1, -2.0, 3.5);
  EXPECT_TRUE(fromPoseMsg(toPoseMsg(T)).isApprox(T, 1e-12));
}

TEST(Frames, LeadingSlashesAreStripped) {
  EXPECT_EQ(stripSlash("/openni_depth_optical_frame"), "openni_depth_optical_frame");
  EXPECT_EQ(stripSlash("//map"), "map");
  EXPECT_EQ(stripSlash("base_link"), "base_link");
  EXPECT_EQ(stripSlash("/"), "");
}

TEST(MapSnapshot, FollowsChangedBlocksAndNoticesAMapReplacedByAnotherOfTheSameGrid) {
  sdf_tracker::VolumeConfig config;
  config.type = sdf_tracker::MapType::kSparse;
  std::mutex mutex;
  std::unique_ptr<sdf_tracker::SparseTsdfMap> live = std::make_unique<sdf_tracker::SparseTsdfMap>(config);
  MapSnapshot snapshot(mutex, [&live] { return live.get(); });
  auto blocksOf = [](const sdf_tracker::TsdfMap* map) {
    return static_cast<const sdf_tracker::SparseTsdfMap&>(*map).blockIndices();
  };
  const sdf_tracker::SparseTsdfMap::BlockIndex a(0, 0, 0), b(5, -1, 2);
  EXPECT_TRUE(blocksOf(snapshot.update()).empty());
  live->allocate(a).changed_at = live->beginRevision();
  EXPECT_EQ(blocksOf(snapshot.update()), std::vector<sdf_tracker::SparseTsdfMap::BlockIndex>{a});
  // A map of the same grid and revision loaded in its place (as ~load_volume does).
  auto loaded = std::make_unique<sdf_tracker::SparseTsdfMap>(config);
  loaded->allocate(b).changed_at = loaded->beginRevision();
  live = std::move(loaded);
  EXPECT_EQ(blocksOf(snapshot.update()), std::vector<sdf_tracker::SparseTsdfMap::BlockIndex>{b});
}

TEST(MapSnapshot, LetsGoOfTheBlocksTheLiveMapSwappedOutAndTakesThemBackWhenReadBack) {
  using BlockIndex = sdf_tracker::SparseTsdfMap::BlockIndex;
  sdf_tracker::VolumeConfig config;
  config.type = sdf_tracker::MapType::kSparse;
  std::mutex mutex;
  sdf_tracker::SparseTsdfMap live(config);
  MapSnapshot snapshot(mutex, [&live] { return &live; });
  const BlockIndex near(0, 0, 0), far(40, 0, 0);
  const uint64_t fused = live.beginRevision();
  for (const BlockIndex& index : {near, far}) {
    sdf_tracker::VoxelBlock& block = live.allocate(index);
    block.voxels[7] = sdf_tracker::Voxel{0.01f, 3.0f};
    block.changed_at = fused;
  }
  auto blocksOf = [](const sdf_tracker::TsdfMap* map) {
    return static_cast<const sdf_tracker::SparseTsdfMap&>(*map).blockIndices();
  };
  ASSERT_EQ(blocksOf(snapshot.update()), (std::vector<BlockIndex>{near, far}));

  // A budget of one byte swaps out every block but those around the camera.
  sdf_tracker::MapMemoryBudget budget(1, ::testing::TempDir());
  ASSERT_EQ(budget.evict(&live, sdf_tracker::BlockBox{near, near}, Eigen::Vector3f::Zero()), 1u);
  EXPECT_EQ(blocksOf(snapshot.update()), std::vector<BlockIndex>{near}) << "the copy is bounded as the live map is";

  ASSERT_EQ(budget.restore(&live, sdf_tracker::BlockBox{far, far}), 1u);
  const auto* copy = static_cast<const sdf_tracker::SparseTsdfMap*>(snapshot.update());
  EXPECT_EQ(blocksOf(copy), (std::vector<BlockIndex>{near, far}));
  const sdf_tracker::Voxel back = copy->find(far)->voxels[7];
  EXPECT_EQ(back.distance_m, 0.01f);
  EXPECT_EQ(back.weight, 3.0f);
}

}  // namespace
}  // namespace sdf_tracker_ros
