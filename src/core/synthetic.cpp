#include "sdf_tracker/core/synthetic.h"

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/core/io.h"
#include "sdf_tracker/core/tum_sequence.h"

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

Scene Scene::indoorRoom() {
  // World: y points down (as the first camera's image), floor at y = 1.3 m.
  Scene scene;
  scene.add(box({0.0, -0.1, 1.0}, {2.5, 1.4, 2.5}, Eigen::Matrix3d::Identity(), true));  // room
  scene.add(box({0.0, 0.5, 1.5}, {0.8, 0.02, 0.45}));                                   // desk top
  for (double sx : {-0.75, 0.75}) {
    for (double z : {1.1, 1.9}) scene.add(box({sx, 0.91, z}, {0.03, 0.39, 0.03}));  // desk legs
  }
  scene.add(sphere({0.35, 0.36, 1.4}, 0.12));                                         // ball on the desk
  scene.add(box({-0.35, 0.36, 1.5}, {0.12, 0.12, 0.1}, rotation(0.0, 0.5, 0.0)));    // turned box on the desk
  scene.add(box({0.0, 0.4, 1.85}, {0.25, 0.08, 0.04}, rotation(0.3, 0.0, 0.0)));     // tilted book stand
  scene.add(box({1.6, 0.3, 3.1}, {0.5, 1.0, 0.35}));                                  // cabinet
  scene.add(box({-1.8, 0.0, 2.2}, {0.4, 0.3, 0.02}, rotation(0.35, 0.8, 0.6)));      // slanted panel
  scene.add(box({-1.0, 1.1, 0.8}, {0.25, 0.2, 0.25}, rotation(0.0, 0.35, 0.0)));     // crate on the floor
  scene.add(sphere({1.0, 1.0, 2.6}, 0.3));                                            // ball on the floor
  return scene;
}

Scene Scene::singleWall() {
  Scene scene;
  scene.add(box({0.0, 0.0, 2.05}, {20.0, 20.0, 0.05}));
  return scene;
}

bool Scene::intersect(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W, double* t,
                      Eigen::Vector3d* normal_W) const {
  *t = kInf;
  for (const Primitive& p : primitives_) {
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

Motion parseMotion(const std::string& name) {
  for (Motion m : {Motion::kDesk, Motion::kSlow, Motion::kFast, Motion::kPlanar, Motion::kLoop}) {
    if (toString(m) == name) return m;
  }
  throw std::invalid_argument("unknown motion \"" + name + "\" (known: desk, slow, fast, planar, loop)");
}

std::string toString(Motion motion) {
  switch (motion) {
    case Motion::kDesk: return "desk";
    case Motion::kSlow: return "slow";
    case Motion::kFast: return "fast";
    case Motion::kPlanar: return "planar";
    case Motion::kLoop: return "loop";
  }
  return "unknown";
}

Eigen::Isometry3d cameraPose(Motion motion, double t_s, double duration_s) {
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

void writeSequence(const std::string& directory, const SequenceSpec& spec) {
  if (spec.frames <= 0 || !(spec.rate_hz > 0.0)) {
    throw std::invalid_argument("a sequence needs frames > 0 and rate_hz > 0 (got " + std::to_string(spec.frames) +
                                ", " + std::to_string(spec.rate_hz) + ")");
  }
  io::makeDirectories(directory + "/depth");
  const Scene scene = spec.motion == Motion::kPlanar ? Scene::singleWall() : Scene::indoorRoom();
  const double duration = spec.frames / spec.rate_hz;
  std::ostringstream depth_list, ground_truth, intrinsics;
  depth_list << "# synthetic depth (sdf_tracker), motion " << toString(spec.motion) << ", noise "
             << (spec.noise.enabled ? "on" : "off") << ", seed " << spec.seed << "\n# timestamp filename\n";
  ground_truth << "# exact ground truth, camera to world\n# timestamp tx ty tz qx qy qz qw\n";
  std::vector<io::StampedPose> poses;
  for (int i = 0; i < spec.frames; ++i) {
    const double t = i / spec.rate_hz;
    const Eigen::Isometry3d T_W_C = cameraPose(spec.motion, t, duration);
    char name[64];
    std::snprintf(name, sizeof(name), "depth/%.6f.png", t);
    io::writeDepthPng(directory + "/" + name, scene.render(spec.camera, T_W_C, spec.noise, spec.seed * 100003u + i),
                      spec.depth_factor);
    depth_list << std::fixed;
    depth_list.precision(6);
    depth_list << t << ' ' << name << '\n';
    poses.push_back({t, T_W_C});
  }
  io::writeTrajectory(directory + "/groundtruth.txt", poses);
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
  // The distortion columns are written even when zero: the reader would otherwise take TUM's
  // published distortion for TUM's intrinsics.
  const LensDistortion& d = spec.camera.distortion;
  intrinsics << "# " << TumSequence::kIntrinsicsColumns << "\n"
             << spec.camera.fx << ' ' << spec.camera.fy << ' ' << spec.camera.cx << ' ' << spec.camera.cy << ' '
             << spec.camera.width << ' ' << spec.camera.height << ' ' << spec.depth_factor << ' ' << d.k1 << ' '
             << d.k2 << ' ' << d.p1 << ' ' << d.p2 << ' ' << d.k3 << '\n';
  io::writeTextFile(directory + "/intrinsics.txt", intrinsics.str());
  io::writeTextFile(directory + "/depth.txt", depth_list.str());
}

}  // namespace sdf_tracker::synthetic
