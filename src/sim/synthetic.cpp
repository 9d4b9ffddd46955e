#include "sdf_tracker/sim/synthetic.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/io/colour_image_file.h"
#include "sdf_tracker/io/depth_png.h"
#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/io/tum_sequence.h"

namespace sdf_tracker::synthetic {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::Matrix3d rotation(double roll_x, double yaw_y, double roll_z) {
  return (Eigen::AngleAxisd(yaw_y, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(roll_x, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(roll_z, Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

Primitive box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity(),
              bool inside = false) {
  Primitive p;
  p.shape = Primitive::Shape::kBox;
  p.centre_W = centre;
  p.half_extent_m = half;
  p.R_W_P = R;
  p.inside = inside;
  return p;
}

Primitive sphere(const Eigen::Vector3d& centre, double radius) {
  Primitive p;
  p.shape = Primitive::Shape::kSphere;
  p.centre_W = centre;
  p.half_extent_m = Eigen::Vector3d::Constant(radius);
  return p;
}

/// Slab test in the box's frame; for a room the far face counts (the ray starts inside).
bool intersectBox(const Primitive& b, const Eigen::Vector3d& o_W, const Eigen::Vector3d& d_W, double* t,
                  Eigen::Vector3d* n_W) {
  const Eigen::Vector3d o = b.R_W_P.transpose() * (o_W - b.centre_W);
  const Eigen::Vector3d d = b.R_W_P.transpose() * d_W;
  double t_near = -kInf, t_far = kInf;
  int axis_near = 0, axis_far = 0;
  for (int a = 0; a < 3; ++a) {
    const double h = b.half_extent_m[a];
    if (std::fabs(d[a]) < 1e-12) {
      if (std::fabs(o[a]) > h) return false;
      continue;
    }
    double t1 = (-h - o[a]) / d[a], t2 = (h - o[a]) / d[a];
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > t_near) t_near = t1, axis_near = a;
    if (t2 < t_far) t_far = t2, axis_far = a;
  }
  if (t_near > t_far) return false;
  const int axis = b.inside ? axis_far : axis_near;
  *t = b.inside ? t_far : t_near;
  if (*t <= 0.0) return false;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[axis] = d[axis] > 0.0 ? -1.0 : 1.0;  // facing the ray either way
  *n_W = b.R_W_P * n;
  return true;
}

bool intersectSphere(const Primitive& s, const Eigen::Vector3d& o_W, const Eigen::Vector3d& d_W, double* t,
                     Eigen::Vector3d* n_W) {
  const Eigen::Vector3d oc = o_W - s.centre_W;
  const double r = s.half_extent_m.x();
  const double b = d_W.dot(oc);
  const double disc = b * b - (oc.squaredNorm() - r * r);
  if (disc < 0.0) return false;
  *t = -b - std::sqrt(disc);
  if (*t <= 0.0) return false;
  *n_W = (oc + *t * d_W) / r;
  return true;
}

/// Look-at with the world's +y as "down" in the image.
Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, double roll_rad) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R << x, y, z;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R * Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = eye;
  return T;
}

}  // namespace

constexpr double kGravity_m_s2 = 9.81;

namespace {

// The indoor room's parts. World: y points down (as the first camera's image), floor at y = 1.3 m.

/// A room seen from within, its floor at y = 1.3 m.
Primitive roomShell(const Eigen::Vector3d& centre, const Eigen::Vector3d& half) {
  return box(centre, half, Eigen::Matrix3d::Identity(), true);
}

/// The desk (its top centred at x = 0, z = 1.5) and what stands on it.
Scene desk() {
  Scene scene;
  scene.add(box({0.0, 0.5, 1.5}, {0.8, 0.02, 0.45}));  // desk top
  for (double sx : {-0.75, 0.75}) {
    for (double z : {1.1, 1.9}) scene.add(box({sx, 0.91, z}, {0.03, 0.39, 0.03}));  // desk legs
  }
  scene.add(sphere({0.35, 0.36, 1.4}, 0.12));                                       // ball on the desk
  scene.add(box({-0.35, 0.36, 1.5}, {0.12, 0.12, 0.1}, rotation(0.0, 0.5, 0.0)));  // turned box on the desk
  scene.add(box({0.0, 0.4, 1.85}, {0.25, 0.08, 0.04}, rotation(0.3, 0.0, 0.0)));   // tilted book stand
  return scene;
}

/// The furniture around the desk.
Scene furniture() {
  Scene scene;
  scene.add(box({1.6, 0.3, 3.1}, {0.5, 1.0, 0.35}));                              // cabinet
  scene.add(box({-1.8, 0.0, 2.2}, {0.4, 0.3, 0.02}, rotation(0.35, 0.8, 0.6)));  // slanted panel
  scene.add(box({-1.0, 1.1, 0.8}, {0.25, 0.2, 0.25}, rotation(0.0, 0.35, 0.0)));  // crate on the floor
  scene.add(sphere({1.0, 1.0, 2.6}, 0.3));                                        // ball on the floor
  return scene;
}

}  // namespace

Scene Scene::indoorRoom() {
  Scene scene;
  scene.add(roomShell({0.0, -0.1, 1.0}, {2.5, 1.4, 2.5}));
  scene.add(desk(), Eigen::Isometry3d::Identity());
  scene.add(furniture(), Eigen::Isometry3d::Identity());
  return scene;
}

Scene Scene::twoIdenticalRooms() {
  Scene scene = indoorRoom();
  scene.add(indoorRoom(), secondRoom());
  return scene;
}

Eigen::Isometry3d Scene::secondRoom() { return Eigen::Isometry3d(Eigen::Translation3d(6.0, 0.0, 0.0)); }

Scene Scene::symmetricRoom() {
  Scene scene;
  scene.add(roomShell({0.0, -0.1, 1.5}, {2.5, 1.4, 2.5}));
  Scene contents = desk();
  contents.add(furniture(), Eigen::Isometry3d::Identity());
  scene.add(contents, Eigen::Isometry3d::Identity());
  scene.add(contents, halfTurnAboutTheDesk());
  return scene;
}

Eigen::Isometry3d Scene::halfTurnAboutTheDesk() {
  const Eigen::Vector3d axis_point(0.0, 0.0, 1.5);
  return Eigen::Translation3d(axis_point) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()) *
         Eigen::Translation3d(-axis_point);
}

Scene Scene::twoIdenticalDesks() {
  Scene scene;
  scene.add(roomShell({1.25, -0.1, 1.5}, {3.25, 1.4, 2.5}));
  scene.add(desk(), Eigen::Isometry3d::Identity());
  scene.add(desk(), secondDesk());
  scene.add(furniture(), Eigen::Isometry3d::Identity());
  return scene;
}

Eigen::Isometry3d Scene::secondDesk() { return Eigen::Isometry3d(Eigen::Translation3d(2.5, 0.0, 0.0)); }

namespace {

// The house's heights: y points down, the floor is at y = 1.3 m and the ceiling 2.5 m above it,
// so a camera at y = 0 is at eye height.
constexpr double kFloorY = 1.3;
constexpr double kCeilingY = -1.2;
constexpr double kWallHalfThickness = 0.05;
constexpr double kDoorTopY = kFloorY - 2.0;

/// A wall from floor to ceiling: in the plane z = at (along_x) or x = at (otherwise), running
/// from `from` to `to` along the other horizontal axis, with 1 m wide doors centred at `doors`.
struct Wall {
  bool along_x;
  double at, from, to;
  std::vector<double> doors;
};

/// The house's shell: x in [0, 12], z in [-4, 6].
constexpr double kHouseMinX = 0.0, kHouseMaxX = 12.0, kHouseMinZ = -4.0, kHouseMaxZ = 6.0;

/// The piece of `wall` from a to b along it, between heights y0 and y1 (y0 < y1).
Primitive wallPiece(const Wall& wall, double a, double b, double y0 = kCeilingY, double y1 = kFloorY) {
  if (wall.along_x) {
    return box({0.5 * (a + b), 0.5 * (y0 + y1), wall.at}, {0.5 * (b - a), 0.5 * (y1 - y0), kWallHalfThickness});
  }
  return box({wall.at, 0.5 * (y0 + y1), 0.5 * (a + b)}, {kWallHalfThickness, 0.5 * (y1 - y0), 0.5 * (b - a)});
}

/// The pieces of `wall` between its doors, and a lintel above each door.
void addWall(Scene* scene, const Wall& wall) {
  double from = wall.from;
  for (double door : wall.doors) {
    scene->add(wallPiece(wall, from, door - 0.5));
    scene->add(wallPiece(wall, door - 0.5, door + 0.5, kCeilingY, kDoorTopY));
    from = door + 0.5;
  }
  scene->add(wallPiece(wall, from, wall.to));
}

/// A box standing on the floor at (x, z), turned by yaw about the vertical.
Primitive onFloor(double x, double z, double half_x, double height, double half_z, double yaw = 0.0) {
  return box({x, kFloorY - 0.5 * height, z}, {half_x, 0.5 * height, half_z}, rotation(0.0, yaw, 0.0));
}

/// What lived-in rooms and corridors have on their walls: a picture (4 cm relief) or a shelf
/// (30 cm deep) every metre of each face inside the house, at heights that vary, so that every
/// view of a wall holds edges across both of its axes; doors are kept clear. The pattern runs on
/// from one face to the next.
void addPicturesAndShelves(Scene* scene, const std::vector<Wall>& walls) {
  constexpr double kSpacing_m = 1.0;
  constexpr double kDoorClearance_m = 0.9;
  int item = 0;
  for (const Wall& wall : walls) {
    for (double side : {-1.0, 1.0}) {
      const double face = wall.at + side * kWallHalfThickness;
      const bool inside_the_shell =
          wall.along_x ? kHouseMinZ < face && face < kHouseMaxZ : kHouseMinX < face && face < kHouseMaxX;
      if (!inside_the_shell) continue;
      for (double s = wall.from + 0.6; s < wall.to - 0.4; s += kSpacing_m, ++item) {
        const bool by_a_door = std::any_of(wall.doors.begin(), wall.doors.end(),
                                           [s](double door) { return std::abs(s - door) < kDoorClearance_m; });
        if (by_a_door) continue;
        const bool shelf = item % 3 == 1;
        const double half_width = shelf ? 0.35 : 0.25;
        const double half_height = shelf ? 0.02 : 0.18;
        const double half_depth = shelf ? 0.15 : 0.02;
        const double centre_y = shelf ? 0.35 + 0.1 * (item % 2) : -0.15 + 0.1 * (item % 4);
        const double off_wall = face + side * half_depth;
        if (wall.along_x) {
          scene->add(box({s, centre_y, off_wall}, {half_width, half_height, half_depth}));
        } else {
          scene->add(box({off_wall, centre_y, s}, {half_depth, half_height, half_width}));
        }
      }
    }
  }
}

}  // namespace

Scene Scene::house(HouseWalls walls) {
  Scene scene;
  // Floor and ceiling over the whole house; the shell; the corridor z in [0, 2]; rooms south
  // (z < 0) at x in [0, 4], [4, 8], [8, 12] and north (z > 2) at x in [0, 6], [6, 12].
  scene.add(box({6.0, kFloorY + 0.05, 1.0}, {6.2, 0.05, 5.2}));
  scene.add(box({6.0, kCeilingY - 0.05, 1.0}, {6.2, 0.05, 5.2}));
  const std::vector<Wall> house_walls = {{true, kHouseMinZ, kHouseMinX, kHouseMaxX, {}},
                                         {true, kHouseMaxZ, kHouseMinX, kHouseMaxX, {}},
                                         {false, kHouseMinX, kHouseMinZ, kHouseMaxZ, {}},
                                         {false, kHouseMaxX, kHouseMinZ, kHouseMaxZ, {}},
                                         {false, 4.0, kHouseMinZ, 0.0, {}},
                                         {false, 8.0, kHouseMinZ, 0.0, {}},
                                         {true, 0.0, kHouseMinX, kHouseMaxX, {2.0, 6.0, 10.0}},
                                         {true, 2.0, kHouseMinX, kHouseMaxX, {3.0, 9.0}},
                                         {false, 6.0, 2.0, kHouseMaxZ, {}}};
  for (const Wall& wall : house_walls) addWall(&scene, wall);
  // Corridor: cabinets against the walls and pictures at eye height, so that its length is seen.
  scene.add(onFloor(4.5, 1.75, 0.3, 1.0, 0.2));
  scene.add(onFloor(7.5, 0.25, 0.4, 0.9, 0.2));
  scene.add(onFloor(11.5, 1.0, 0.25, 1.2, 0.5));
  for (double x : {1.2, 5.2, 10.4}) scene.add(box({x, -0.1, 1.92}, {0.3, 0.2, 0.03}));
  for (double x : {3.6, 7.0, 11.2}) scene.add(box({x, -0.2, 0.08}, {0.25, 0.3, 0.03}));
  // Rooms.
  scene.add(onFloor(1.0, -3.2, 0.5, 0.8, 0.35, 0.2));
  scene.add(onFloor(3.5, -1.0, 0.25, 1.6, 0.25));
  scene.add(sphere({3.3, kFloorY - 0.3, -3.4}, 0.3));
  scene.add(onFloor(5.0, -3.3, 0.6, 0.75, 0.4, -0.3));
  scene.add(onFloor(7.3, -2.0, 0.3, 1.2, 0.6));
  scene.add(sphere({6.0, kFloorY - 0.25, -2.8}, 0.25));
  scene.add(onFloor(9.0, -3.0, 0.4, 1.0, 0.4, 0.6));
  scene.add(onFloor(11.3, -1.5, 0.3, 0.9, 0.8));
  scene.add(box({10.5, -0.3, -3.9}, {0.4, 0.3, 0.02}, rotation(0.3, 0.0, 0.4)));
  scene.add(onFloor(1.0, 5.0, 0.6, 0.8, 0.4));
  scene.add(onFloor(4.5, 3.2, 0.5, 0.5, 0.5, 0.4));
  scene.add(sphere({2.0, kFloorY - 0.3, 4.0}, 0.3));
  scene.add(onFloor(5.5, 5.5, 0.3, 1.8, 0.3));
  scene.add(onFloor(7.0, 5.2, 0.8, 0.75, 0.5, 0.1));
  scene.add(onFloor(11.0, 3.0, 0.4, 1.4, 0.4));
  scene.add(sphere({10.0, kFloorY - 0.25, 5.0}, 0.25));
  if (walls == HouseWalls::kFurnished) addPicturesAndShelves(&scene, house_walls);
  return scene;
}

void Scene::add(const Scene& other, const Eigen::Isometry3d& T_W_other) {
  for (Primitive p : other.primitives_) {
    p.centre_W = T_W_other * p.centre_W;
    p.R_W_P = T_W_other.linear() * p.R_W_P;
    primitives_.push_back(p);
  }
}

Scene Scene::forMotion(Motion motion, HouseWalls walls) {
  if (goesThroughTheHouse(motion)) return house(walls);
  return motion == Motion::kPlanar ? singleWall() : indoorRoom();
}

Scene Scene::singleWall() {
  Scene scene;
  scene.add(box({0.0, 0.0, 2.05}, {20.0, 20.0, 0.05}));
  return scene;
}

namespace {

/// Whether the ray origin_W + t dir_W (t > 0) can meet `p` at a t below `t_best`, judged by the
/// sphere that holds `p`: false only when it surely cannot, so that skipping `p` changes no hit.
/// A room seen from inside always can.
bool mayHitBefore(const Primitive& p, const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W, double t_best) {
  if (p.inside) return true;
  const double radius = p.shape == Primitive::Shape::kSphere ? p.half_extent_m.x() : p.half_extent_m.norm();
  const double reach = radius + 1e-6 * (1.0 + radius);  // a margin far above either test's rounding
  const double speed = dir_W.norm();
  const Eigen::Vector3d to_centre = p.centre_W - origin_W;
  const double distance = to_centre.norm();
  if (distance <= reach) return true;                           // the ray starts within the sphere
  if ((distance - reach) / speed > t_best) return false;        // all of it lies beyond the best hit
  const double along = dir_W.dot(to_centre) / speed;
  if (along <= 0.0) return false;                               // it lies behind the ray
  return to_centre.squaredNorm() - along * along <= reach * reach;  // the ray's line passes within reach
}

}  // namespace

bool Scene::intersect(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W, double* t,
                      Eigen::Vector3d* normal_W) const {
  *t = kInf;
  for (const Primitive& p : primitives_) {
    if (!mayHitBefore(p, origin_W, dir_W, *t)) continue;
    double t_hit;
    Eigen::Vector3d n;
    const bool hit = p.shape == Primitive::Shape::kBox ? intersectBox(p, origin_W, dir_W, &t_hit, &n)
                                                       : intersectSphere(p, origin_W, dir_W, &t_hit, &n);
    if (hit && t_hit < *t) {
      *t = t_hit;
      *normal_W = n;
    }
  }
  return std::isfinite(*t);
}

DepthImage Scene::render(const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C, const NoiseModel& noise,
                         uint32_t seed) const {
  DepthImage depth(camera.width, camera.height);
  const double max_incidence_cos = std::cos(noise.max_incidence_deg * M_PI / 180.0);
  // The depth bias grows as r^2 / r_corner^2, r_corner the farthest corner pixel's distance to
  // the principal point.
  double corner_r2 = 0.0;
  for (double u : {0.0, camera.width - 1.0}) {
    for (double v : {0.0, camera.height - 1.0}) {
      corner_r2 = std::max(corner_r2, (u - camera.cx) * (u - camera.cx) + (v - camera.cy) * (v - camera.cy));
    }
  }
  const double bias_per_r2 = noise.depth_bias != 0.0 && corner_r2 > 0.0 ? noise.depth_bias / corner_r2 : 0.0;
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < camera.height; ++v) {
    std::mt19937 rng(seed * 2654435761u + static_cast<uint32_t>(v));  // one stream per row: thread-count independent
    std::normal_distribution<double> gaussian(0.0, 1.0);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (int u = 0; u < camera.width; ++u) {
      // The ray of the ideal lens that the camera's lens bends onto pixel (u, v).
      const Eigen::Vector2d ideal =
          camera.distortion.undistort({(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy});
      const Eigen::Vector3d ray_C(ideal.x(), ideal.y(), 1.0);
      const Eigen::Vector3d dir_W = (T_W_C.linear() * ray_C).normalized();
      double t;
      Eigen::Vector3d n_W;
      if (!intersect(T_W_C.translation(), dir_W, &t, &n_W)) continue;
      double z = t / ray_C.norm();  // depth along the optical axis
      z *= 1.0 + bias_per_r2 * ((u - camera.cx) * (u - camera.cx) + (v - camera.cy) * (v - camera.cy));
      if (noise.enabled) {
        const double cos_incidence = std::fabs(n_W.dot(dir_W));
        const double noise_draw = gaussian(rng);
        const double dropout_draw = uniform(rng);
        if (cos_incidence < max_incidence_cos || z > noise.max_range_m || dropout_draw < noise.dropout_probability) {
          continue;
        }
        const double theta = std::acos(std::min(1.0, cos_incidence));
        const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4) +
                             0.0001 / std::sqrt(z) * theta * theta / ((M_PI / 2 - theta) * (M_PI / 2 - theta));
        z += noise.axial_noise_scale * sigma * noise_draw;
        if (noise.disparity_subpixels > 0) {
          const double steps = noise.disparity_subpixels;
          z = noise.focal_baseline_px_m / (std::round(steps * noise.focal_baseline_px_m / z) / steps);
        }
      }
      depth.at(u, v) = static_cast<float>(z);
    }
  }
  return depth;
}

void checkDepthBias(double depth_bias, const std::string& what) {
  // Written so that NaN fails the comparison.
  if (!(std::abs(depth_bias) <= kMaxDepthBias)) {
    std::ostringstream message;
    message << what << ": the depth bias must be finite and in [" << -kMaxDepthBias << ", " << kMaxDepthBias
            << "], got " << depth_bias;
    throw std::invalid_argument(message.str());
  }
}

Motion parseMotion(const std::string& name) {
  std::string known;
  for (Motion m : {Motion::kDesk, Motion::kSlow, Motion::kFast, Motion::kPlanar, Motion::kLoop, Motion::kWalk,
                   Motion::kCorridor, Motion::kRoundTrip}) {
    if (toString(m) == name) return m;
    known += (known.empty() ? "" : ", ") + toString(m);
  }
  throw std::invalid_argument("unknown motion \"" + name + "\" (known: " + known + ")");
}

std::string toString(Motion motion) {
  switch (motion) {
    case Motion::kDesk: return "desk";
    case Motion::kSlow: return "slow";
    case Motion::kFast: return "fast";
    case Motion::kPlanar: return "planar";
    case Motion::kLoop: return "loop";
    case Motion::kWalk: return "walk";
    case Motion::kCorridor: return "corridor";
    case Motion::kRoundTrip: return "round-trip";
  }
  return "unknown";
}

bool goesThroughTheHouse(Motion motion) {
  return motion == Motion::kWalk || motion == Motion::kCorridor || motion == Motion::kRoundTrip;
}

namespace {

/// A walk through the house: a Catmull-Rom curve through waypoints on the floor plan (x, z),
/// sampled densely and parametrised by arc length. Its ends are straight when the first three and
/// the last three waypoints lie on a line.
class WalkPath {
 public:
  explicit WalkPath(const std::vector<Eigen::Vector2d>& waypoints) {
    constexpr int kSamplesPerSegment = 64;
    for (size_t i = 0; i + 1 < waypoints.size(); ++i) {
      const Eigen::Vector2d& p0 = waypoints[i == 0 ? 0 : i - 1];
      const Eigen::Vector2d& p1 = waypoints[i];
      const Eigen::Vector2d& p2 = waypoints[i + 1];
      const Eigen::Vector2d& p3 = waypoints[std::min(i + 2, waypoints.size() - 1)];
      for (int k = 0; k < kSamplesPerSegment; ++k) {
        const double t = static_cast<double>(k) / kSamplesPerSegment;
        const Eigen::Vector2d p = 0.5 * ((2.0 * p1) + (p2 - p0) * t + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t * t +
                                         (3.0 * p1 - p0 - 3.0 * p2 + p3) * t * t * t);
        append(p);
      }
    }
    append(waypoints.back());
  }

  double length() const { return arc_.back(); }

  /// The point at arc length s, clamped to the ends.
  Eigen::Vector2d at(double s) const {
    s = std::max(0.0, std::min(s, length()));
    const size_t i = std::min<size_t>(std::upper_bound(arc_.begin(), arc_.end(), s) - arc_.begin(), arc_.size() - 1);
    if (i == 0) return points_.front();
    const double f = (s - arc_[i - 1]) / std::max(arc_[i] - arc_[i - 1], 1e-12);
    return points_[i - 1] + f * (points_[i] - points_[i - 1]);
  }

 private:
  void append(const Eigen::Vector2d& p) {
    arc_.push_back(points_.empty() ? 0.0 : arc_.back() + (p - points_.back()).norm());
    points_.push_back(p);
  }
  std::vector<Eigen::Vector2d> points_;
  std::vector<double> arc_;
};

/// The walk: along the corridor and round every room.
const WalkPath& houseWalk() {
  static const WalkPath path({
      {1.0, 1.0},  {2.0, 1.0},  {2.0, -1.0}, {3.0, -2.5}, {1.5, -3.0}, {1.0, -1.8}, {2.0, -0.8},   // room 1
      {2.2, 1.0},  {3.0, 1.2},  {3.0, 3.0},  {4.5, 4.5},  {2.0, 5.0},  {1.5, 3.5},  {3.0, 2.8},   // room 4
      {3.2, 1.0},  {6.0, 1.0},  {6.0, -1.0}, {7.0, -2.5}, {5.0, -3.0}, {5.5, -1.2}, {6.0, 0.6},   // room 2
      {7.5, 1.1},  {9.0, 1.0},  {9.0, 3.0},  {10.5, 4.5}, {7.5, 4.6},  {8.0, 3.0},  {9.0, 1.6},   // room 5
      {10.0, 1.0}, {10.0, -1.0}, {11.0, -2.8}, {9.0, -3.0}, {9.6, -1.0}, {10.0, 1.0}, {7.0, 1.0},  // room 3
      {4.0, 1.0},  {1.5, 1.0}});                                                                    // back
  return path;
}

/// The round trip: east down the corridor's middle, round room 5 (north, door at x = 9) and back
/// out, west down the corridor, round room 1 (south, door at x = 2), and out onto the corridor
/// where it started, straight along +x over its first and last metre. Every waypoint keeps 0.3 m
/// or more from the walls, from the shelves on them and from the furniture's footprints.
const WalkPath& roundTrip() {
  static const WalkPath path({
      {3.3, 1.0}, {4.5, 1.0}, {6.0, 1.0}, {7.6, 1.0},                                               // corridor east
      {8.7, 1.3}, {9.1, 2.1}, {8.3, 2.8}, {7.4, 3.0}, {6.8, 3.6}, {7.4, 4.2}, {8.5, 4.4}, {9.4, 4.3},  // room 5
      {10.2, 4.1}, {10.1, 3.3}, {9.4, 2.7}, {9.0, 1.8},
      {8.0, 1.1}, {6.0, 1.0}, {4.0, 1.0},                                                           // corridor west
      {2.9, 0.8}, {2.1, -0.1}, {2.6, -1.2}, {2.5, -2.5}, {2.3, -3.2}, {1.7, -2.4}, {0.8, -1.8},     // room 1
      {1.3, -1.1}, {1.9, -0.6},
      {1.9, 0.3}, {1.3, 0.7}, {0.95, 1.0}, {1.3, 1.35}, {2.0, 1.15}, {2.5, 1.0}, {2.9, 1.0}, {3.3, 1.0}});  // turning back
  return path;
}

constexpr double kWalkSpeed_m_s = 0.5;

/// Carrying the camera along `path` at kWalkSpeed_m_s at eye height, looking where it goes, the
/// head swaying slowly and bobbing with the steps. With `settle`, the sway fades out over the
/// path's last kSettle_m and the camera stops at its end looking along the path, as it started
/// (the sway is zero at t = 0): a path that ends where it began ends in the pose it began in.
Eigen::Isometry3d handHeldPose(const WalkPath& path, double t_s, bool settle) {
  constexpr double kSettle_m = 1.5;
  const double s = kWalkSpeed_m_s * t_s;
  const Eigen::Vector2d here = path.at(s);
  const double f = settle ? std::max(0.0, std::min(1.0, (path.length() - s) / kSettle_m)) : 1.0;
  const double sway = f * f * (3.0 - 2.0 * f);  // fades out at rest
  // Looking where the path goes over the next and last 0.4 m smooths the turns at the waypoints;
  // a slow sway of the head sweeps the walls.
  Eigen::Vector2d heading = path.at(s + 0.4) - path.at(s - 0.4);
  if (heading.norm() < 1e-6) heading = Eigen::Vector2d(1.0, 0.0);
  const double yaw = std::atan2(heading.x(), heading.y()) + sway * 0.25 * std::sin(0.7 * t_s);
  const double pitch_down = 0.25 + sway * 0.08 * std::sin(0.45 * t_s);
  const Eigen::Vector3d eye(here.x(), sway * 0.02 * std::sin(2.0 * M_PI * 1.8 * t_s), here.y());
  const Eigen::Vector3d forward(std::sin(yaw) * std::cos(pitch_down), std::sin(pitch_down),
                                std::cos(yaw) * std::cos(pitch_down));
  return lookAt(eye, eye + forward, sway * 0.03 * std::sin(0.9 * t_s));
}

/// The corridor drive: down the house's corridor (x from 0.8 to 10.4 m, 1 m from either wall),
/// turning on the spot at each end, back, and again; the camera 0.4 m above the floor looks 50
/// degrees to the left of the way the robot drives and 8 degrees down, and shakes by 2 mm.
Eigen::Isometry3d corridorPose(double t_s) {
  constexpr double kFromX = 0.8, kToX = 10.4, kZ = 1.0, kTurn_s = 6.0;  // short of the cabinet at x = 11.25
  constexpr double kEyeY = kFloorY - 0.4;  // the vertical is -y
  constexpr double kSideways_rad = 50.0 * M_PI / 180.0, kDown_rad = 8.0 * M_PI / 180.0;
  const double leg_s = (kToX - kFromX) / kWalkSpeed_m_s;
  const double t = std::fmod(std::max(t_s, 0.0), 2.0 * (leg_s + kTurn_s));
  auto eased = [](double f) { return f * f * (3.0 - 2.0 * f); };  // turns start and end at rest
  double x, heading_rad;  // heading 0: along +x
  if (t < leg_s) {
    x = kFromX + kWalkSpeed_m_s * t, heading_rad = 0.0;
  } else if (t < leg_s + kTurn_s) {
    x = kToX, heading_rad = M_PI * eased((t - leg_s) / kTurn_s);
  } else if (t < 2.0 * leg_s + kTurn_s) {
    x = kToX - kWalkSpeed_m_s * (t - leg_s - kTurn_s), heading_rad = M_PI;
  } else {
    x = kFromX, heading_rad = M_PI + M_PI * eased((t - 2.0 * leg_s - kTurn_s) / kTurn_s);
  }
  // With y down, the robot's left of heading +x is +z.
  const double look_rad = heading_rad + kSideways_rad;
  const Eigen::Vector3d forward(std::cos(look_rad) * std::cos(kDown_rad), std::sin(kDown_rad),
                                std::sin(look_rad) * std::cos(kDown_rad));
  const Eigen::Vector3d eye(x, kEyeY + 0.002 * std::sin(2.0 * M_PI * 3.0 * t_s), kZ);
  return lookAt(eye, eye + forward, 0.0);
}

}  // namespace

Eigen::Isometry3d cameraPose(Motion motion, double t_s, double duration_s) {
  if (motion == Motion::kWalk) return handHeldPose(houseWalk(), t_s, false);
  if (motion == Motion::kRoundTrip) return handHeldPose(roundTrip(), t_s, true);
  if (motion == Motion::kCorridor) return corridorPose(t_s);
  if (motion == Motion::kPlanar) {
    // Facing the wall 2 m away, sliding sideways and up/down: nothing fixes x, y or the roll.
    return lookAt({0.6 * std::sin(0.5 * t_s), 0.2 * std::sin(0.8 * t_s), 0.0},
                  {0.6 * std::sin(0.5 * t_s), 0.2 * std::sin(0.8 * t_s), 2.0}, 0.0);
  }
  if (motion == Motion::kLoop) {
    const double a = 2.0 * M_PI * t_s / duration_s;
    const Eigen::Vector3d desk(0.0, 0.45, 1.5);
    return lookAt(desk + Eigen::Vector3d(-1.4 * std::sin(a), -0.6 + 0.1 * std::sin(2 * a), -1.4 * std::cos(a)),
                  desk, 0.05 * std::sin(3 * a));
  }
  const double speed = motion == Motion::kSlow ? 0.5 : motion == Motion::kFast ? 2.0 : 1.0;
  const double s = speed * t_s;  // path parameter
  const Eigen::Vector3d eye(0.7 * std::sin(0.45 * s), -0.1 + 0.15 * std::sin(0.9 * s + 0.5),
                            0.25 * std::sin(0.35 * s + 1.0) - 0.2);
  const Eigen::Vector3d target(0.2 * std::sin(0.7 * s), 0.4 + 0.1 * std::sin(1.1 * s), 1.5 + 0.25 * std::sin(0.5 * s));
  return lookAt(eye, target, 0.12 * std::sin(0.6 * s));
}

void writeTumFolder(const std::string& directory, const std::string& comment,
                    const std::vector<io::StampedPose>& poses, const std::vector<io::StampedPose>& ground_truth,
                    const std::function<DepthImage(size_t)>& render, const PinholeCamera& camera,
                    double depth_factor) {
  io::makeDirectories(directory + "/depth");
  std::ostringstream depth_list, intrinsics;
  depth_list << "# " << comment << "\n# timestamp filename\n" << std::fixed << std::setprecision(6);
  for (size_t i = 0; i < poses.size(); ++i) {
    char name[64];
    std::snprintf(name, sizeof(name), "depth/%.6f.png", poses[i].timestamp_s);
    io::writeDepthPng(directory + "/" + name, render(i), depth_factor);
    depth_list << poses[i].timestamp_s << ' ' << name << '\n';
  }
  io::writeTrajectory(directory + "/groundtruth.txt", ground_truth);
  // The distortion columns are written even when zero: the reader would otherwise take TUM's
  // published distortion for TUM's intrinsics.
  const LensDistortion& d = camera.distortion;
  intrinsics << "# " << TumSequence::kIntrinsicsColumns << "\n"
             << camera.fx << ' ' << camera.fy << ' ' << camera.cx << ' ' << camera.cy << ' ' << camera.width << ' '
             << camera.height << ' ' << depth_factor << ' ' << d.k1 << ' ' << d.k2 << ' ' << d.p1 << ' ' << d.p2
             << ' ' << d.k3 << '\n';
  io::writeTextFile(directory + "/intrinsics.txt", intrinsics.str());
  io::writeTextFile(directory + "/depth.txt", depth_list.str());
}

void writeSequence(const std::string& directory, const SequenceSpec& spec) {
  if (spec.frames <= 0 || !(spec.rate_hz > 0.0)) {
    throw std::invalid_argument("a sequence needs frames > 0 and rate_hz > 0 (got " + std::to_string(spec.frames) +
                                ", " + std::to_string(spec.rate_hz) + ")");
  }
  checkDepthBias(spec.noise.depth_bias, "noise.depth_bias");
  const Scene scene = Scene::forMotion(spec.motion, spec.house_walls);
  const double duration = spec.frames / spec.rate_hz;
  std::vector<io::StampedPose> poses;
  for (int i = 0; i < spec.frames; ++i) {
    const double t = i / spec.rate_hz;
    poses.push_back({t, cameraPose(spec.motion, t, duration)});
  }
  std::ostringstream comment;
  comment << "synthetic depth (sdf_tracker), motion " << toString(spec.motion) << ", noise "
          << (spec.noise.enabled ? "on" : "off");
  if (spec.noise.depth_bias != 0.0) comment << ", depth bias " << spec.noise.depth_bias;
  comment << ", seed " << spec.seed << (spec.house_walls == HouseWalls::kBare ? ", bare walls" : "");
  writeTumFolder(
      directory, comment.str(), poses, poses,
      [&](size_t i) { return scene.render(spec.camera, poses[i].T_W_C, spec.noise, spec.seed * 100003u + i); },
      spec.camera, spec.depth_factor);
  if (spec.odometry) io::writeTrajectory(directory + "/odometry.txt", wheelOdometry(poses, *spec.odometry));
  if (spec.colour) {
    io::makeDirectories(directory + "/rgb");
    std::ostringstream colour_list;
    colour_list << "# " << comment.str() << ": colour registered to the depth\n# timestamp filename\n" << std::fixed
                << std::setprecision(6);
    for (const io::StampedPose& pose : poses) {
      char name[64];
      std::snprintf(name, sizeof(name), "rgb/%.6f.png", pose.timestamp_s);
      io::writeColourImage(directory + "/" + name, renderColour(scene, spec.camera, pose.T_W_C));
      colour_list << pose.timestamp_s << ' ' << name << '\n';
    }
    io::writeTextFile(directory + "/rgb.txt", colour_list.str());
  }
  // What a resting accelerometer fixed to the depth camera reads (gravity's reaction, up: -y in
  // this world), at 100 Hz from half a second before the first frame, in the camera's frame.
  std::ostringstream accelerometer;
  accelerometer << "# accelerometer (m/s^2) in the depth camera's optical frame, gravity only\n"
                << "# timestamp ax ay az\n" << std::fixed;
  const Eigen::Vector3d up_W(0.0, -kGravity_m_s2, 0.0);
  for (double t = -0.5; t <= duration; t += 0.01) {
    const Eigen::Vector3d a_C = cameraPose(spec.motion, t, duration).linear().transpose() * up_W;
    accelerometer << std::setprecision(6) << t << ' ' << std::setprecision(5) << a_C.x() << ' ' << a_C.y() << ' '
                  << a_C.z() << '\n';
  }
  io::writeTextFile(directory + "/accelerometer.txt", accelerometer.str());
}

Rgb surfaceColour(const Eigen::Vector3d& p_W) {
  static constexpr Rgb kPalette[6] = {{200, 60, 50}, {60, 170, 70}, {50, 80, 200}, {220, 200, 60}, {150, 70, 170},
                                      {60, 180, 190}};
  const Eigen::Vector3d tile = ((p_W.array() - kColourTileOffset_m) / kColourTile_m).floor();
  const long index = static_cast<long>(tile.x()) + 2 * static_cast<long>(tile.y()) + 3 * static_cast<long>(tile.z());
  return kPalette[((index % 6) + 6) % 6];
}

ColourImage renderColour(const Scene& scene, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C) {
  NoiseModel exact;
  exact.enabled = false;
  const DepthImage depth = scene.render(camera, T_W_C, exact, 0);
  ColourImage colour(camera.width, camera.height);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const float z = depth.at(u, v);
      if (!DepthImage::isMeasurement(z)) continue;
      const Rgb c = surfaceColour(T_W_C * camera.backProject(u, v, z).cast<double>());
      std::copy(c.begin(), c.end(), colour.at(u, v));
    }
  }
  return colour;
}

DepthImage withoutRightHalf(DepthImage depth) {
  for (int v = 0; v < depth.height(); ++v) {
    for (int u = depth.width() / 2; u < depth.width(); ++u) depth.at(u, v) = 0.0f;
  }
  return depth;
}

}  // namespace sdf_tracker::synthetic
