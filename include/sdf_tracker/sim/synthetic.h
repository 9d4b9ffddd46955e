#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/colour_image.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/sim/wheel_odometry.h"
#include "sdf_tracker/surface/surface.h"

/// Analytic indoor scenes rendered along scripted camera paths, with exact ground truth: the
/// project's own test data and the default sequence of the main job.
namespace sdf_tracker::synthetic {

/// An oriented box (a room when `inside` is true: rays hit its walls from within) or a sphere.
struct Primitive {
  enum class Shape { kBox, kSphere } shape = Shape::kBox;
  Eigen::Vector3d centre_W = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_W_P = Eigen::Matrix3d::Identity();  ///< box axes in the world
  Eigen::Vector3d half_extent_m = Eigen::Vector3d::Ones();  ///< box half sizes; sphere radius in x
  bool inside = false;
};

/// Kinect v1-like depth noise (Nguyen, Izadi and Lovell, 3DIMPVT 2012) and sensor limits.
struct NoiseModel {
  /// The random part (Gaussian noise, dropouts, quantisation) and the range and incidence limits;
  /// not depth_bias, which applies either way.
  bool enabled = true;
  double max_range_m = 4.5;
  double max_incidence_deg = 78.0;  ///< more grazing surfaces return nothing
  double dropout_probability = 0.01;
  /// Disparity quantisation: 1/8 pixel of a structured-light sensor with this focal length x
  /// baseline product [px m].
  double focal_baseline_px_m = 580.0 * 0.075;
  /// Disparity steps per pixel (8 for a Kinect v1); 0 turns quantisation off.
  int disparity_subpixels = 8;
  /// Scales the axial Gaussian noise (1 = the fitted model, 0 = none).
  double axial_noise_scale = 1.0;
  /// A systematic depth error fixed in the image, as an uncalibrated Kinect has: the relative
  /// error at the image's corners, growing with the square of the distance from the principal
  /// point. Depth z becomes z * (1 + depth_bias * r^2 / r_corner^2), r the pixel's distance to
  /// (cx, cy) and r_corner the largest distance from (cx, cy) to a corner pixel; 0 = none. It is
  /// applied to the true depth, before the noise and the quantisation, whether `enabled` or not:
  /// it is no random draw, the same in every frame.
  double depth_bias = 0.0;
};

/// The largest depth_bias magnitude the sequences take: 10 % at the corners.
constexpr double kMaxDepthBias = 0.1;
/// Throws std::invalid_argument("<what>: ...", with the value) unless `depth_bias` is finite and
/// in [-kMaxDepthBias, kMaxDepthBias].
void checkDepthBias(double depth_bias, const std::string& what);

enum class Motion;

/// What the house has on its walls.
enum class HouseWalls {
  kFurnished,  ///< a picture or a shelf every metre of every wall, as in a lived-in flat
  kBare,       ///< bare but for six pictures in the corridor: close to a wall the view holds one plane,
               ///< which depth alone cannot place
};

class Scene {
 public:
  /// A room with a desk, objects on it, a cabinet and a slanted panel: every axis constrained.
  static Scene indoorRoom();
  /// One large wall and nothing else: three degrees of freedom unconstrained.
  static Scene singleWall();
  /// A 12 m x 10 m flat: a 2 m wide corridor along x with three rooms on one side and two on the
  /// other, doors, furniture, and pictures on the corridor's walls; `walls` says what else the
  /// walls carry.
  static Scene house(HouseWalls walls = HouseWalls::kFurnished);
  /// The scene a path is made for (`walls`: the house's, for the paths through it).
  static Scene forMotion(Motion motion, HouseWalls walls = HouseWalls::kFurnished);

  /// Two copies of the indoor room side by side, the second at secondRoom(), each closed:
  /// standing in either, nothing tells which it is.
  static Scene twoIdenticalRooms();
  static Eigen::Isometry3d secondRoom();  ///< 6 m along x
  /// The indoor room's desk and furniture twice, the copy turned half round the vertical axis
  /// through the desk (halfTurnAboutTheDesk()), in a room as wide as it is deep and centred on it:
  /// every view is the same as the one from the opposite side of the desk.
  static Scene symmetricRoom();
  static Eigen::Isometry3d halfTurnAboutTheDesk();
  /// A wider room with the indoor room's desk twice, the second at secondDesk(), and its furniture
  /// once, around the first desk: a view of either desk is the same but for what surrounds it.
  static Scene twoIdenticalDesks();
  static Eigen::Isometry3d secondDesk();  ///< 2.5 m along x

  void add(const Primitive& p) { primitives_.push_back(p); }
  /// Adds every primitive of `other`, moved by T_W_other.
  void add(const Scene& other, const Eigen::Isometry3d& T_W_other);

  /// Distance along a unit ray to the first surface and that surface's normal; false if none.
  bool intersect(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W, double* t,
                 Eigen::Vector3d* normal_W) const;

  /// Renders a depth image (metres, 0 = none) from T_W_C. With noise enabled, `seed` makes the
  /// result repeatable and independent of the thread count.
  DepthImage render(const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C, const NoiseModel& noise,
                    uint32_t seed) const;

 private:
  std::vector<Primitive> primitives_;
};

enum class Motion {
  kDesk,    ///< hand-held motion around a desk: translation and rotation on every axis
  kSlow,    ///< the same path at half speed
  kFast,    ///< the same path at twice the speed
  kPlanar,  ///< sliding along a single wall: degenerate geometry
  kLoop,    ///< a closed circle around the desk, ending where it started
  kWalk,    ///< walking at 0.5 m/s through the house: along the corridor and round every room
  kCorridor,  ///< a robot driving at 0.5 m/s down the house's corridor and back, its camera 0.4 m
              ///< above the floor looking 50 degrees to the side: the floor and a wall, whose length
              ///< only the pictures, cabinets and doors on it place
  kRoundTrip,  ///< a hand-held walk at 0.5 m/s, as the walk, down the corridor, round two rooms and
               ///< back, ending at rest where it started and looking the same way: its last frames
               ///< see what its first saw
};
Motion parseMotion(const std::string& name);  ///< throws std::invalid_argument
std::string toString(Motion motion);
/// Whether the path goes through the house (the walk, the corridor and the round trip).
bool goesThroughTheHouse(Motion motion);

/// Camera to world at time t [s] along a path. duration_s only sets the loop's period; the walk
/// and the round trip keep their speed and their paths (about 50 m and 37 m) whatever the
/// duration, the round trip standing still at its end once it is done.
Eigen::Isometry3d cameraPose(Motion motion, double t_s, double duration_s);

struct SequenceSpec {
  Motion motion = Motion::kDesk;
  int frames = 300;
  double rate_hz = 30.0;
  NoiseModel noise;
  uint32_t seed = 1;
  HouseWalls house_walls = HouseWalls::kFurnished;  ///< what the house has on its walls (goesThroughTheHouse)
  PinholeCamera camera = PinholeCamera::tumFreiburg1();
  double depth_factor = 5000.0;
  /// Also write odometry.txt: the camera's poses as a wheel odometry of this model reports them.
  std::optional<WheelOdometryModel> odometry;
  /// Also write rgb/ and rgb.txt: colour images registered to the depth (renderColour), at the
  /// depth's timestamps.
  bool colour = false;
};

/// The colour of every scene's surfaces at p_W: tiles of kColourTile_m along each world axis,
/// each one of six colours, so that a map's colours can be checked against it anywhere. The tiles'
/// edges lie kColourTileOffset_m past the multiples of kColourTile_m: an odd amount, so that no
/// wall or box face of the scenes (at round coordinates) lies on an edge, where the colour would
/// flip with the last bit of the depth.
constexpr double kColourTile_m = 0.25;
constexpr double kColourTileOffset_m = 0.0731;
Rgb surfaceColour(const Eigen::Vector3d& p_W);
/// What a colour camera registered to the depth camera sees from T_W_C: the surface colour at
/// each pixel's exact depth; black where the ray meets nothing.
ColourImage renderColour(const Scene& scene, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C);

/// Writes depth/, depth.txt, groundtruth.txt, intrinsics.txt and accelerometer.txt (and
/// odometry.txt, rgb/ and rgb.txt) under `directory` (created).
void writeSequence(const std::string& directory, const SequenceSpec& spec);

/// Writes render(i), taken at poses[i], as depth/ and depth.txt (headed by `comment`), with
/// groundtruth.txt (`ground_truth`: the poses, or a longer recording's that holds them) and
/// intrinsics.txt, under `directory` (created): a TUM folder.
void writeTumFolder(const std::string& directory, const std::string& comment,
                    const std::vector<io::StampedPose>& poses, const std::vector<io::StampedPose>& ground_truth,
                    const std::function<DepthImage(size_t)>& render, const PinholeCamera& camera,
                    double depth_factor);

/// The image with its right half (columns from width / 2) emptied: a view of which a sensor, or a
/// session, saw only the left half.
DepthImage withoutRightHalf(DepthImage depth);

}  // namespace sdf_tracker::synthetic
