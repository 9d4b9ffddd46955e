#include "sdf_tracker/sim/relocalisation_cases.h"

#include <functional>
#include <stdexcept>

#include "sdf_tracker/io/files.h"

namespace sdf_tracker::synthetic {

namespace {

/// Frames along the loop round the desk (12 s a lap) at 15 Hz, path times [t0_s, t1_s), in the
/// room placed at T_W_room, stamped from `stamp0_s` on.
void addLoop(std::vector<io::StampedPose>* poses, double t0_s, double t1_s, const Eigen::Isometry3d& T_W_room,
             double stamp0_s) {
  constexpr double kRate_hz = 15.0;
  for (int n = 0; t0_s + n / kRate_hz < t1_s - 1e-9; ++n) {
    const double t = t0_s + n / kRate_hz;
    poses->push_back({stamp0_s + n / kRate_hz, T_W_room * cameraPose(Motion::kLoop, t, 12.0)});
  }
}

/// After the first session's last stamp: a second session starts later.
double afterMapping(const RelocalisationCase& c) { return c.mapping.back().timestamp_s + 1.0; }

RelocalisationCase halfNew() {
  RelocalisationCase c;
  c.description =
      "the first session saw the left half of each view along 2 s of the loop round the desk; the second "
      "starts where the first left off, its first view half ground the map never saw";
  c.scene = Scene::indoorRoom();
  addLoop(&c.mapping, 0.0, 2.0, Eigen::Isometry3d::Identity(), 0.0);
  c.mapping_saw_left_half_only = true;
  addLoop(&c.session, 2.0, 3.0, Eigen::Isometry3d::Identity(), afterMapping(c));
  return c;
}

RelocalisationCase twoRooms() {
  RelocalisationCase c;
  c.description =
      "two identical rooms, each mapped along the same 3 s of the loop; the second session walks 1.5 s of that "
      "stretch in the first room: nothing tells which room it is in";
  c.scene = Scene::twoIdenticalRooms();
  addLoop(&c.mapping, 0.0, 3.0, Eigen::Isometry3d::Identity(), 0.0);
  addLoop(&c.mapping, 0.0, 3.0, Scene::secondRoom(), 3.0);
  addLoop(&c.session, 1.0, 2.5, Eigen::Isometry3d::Identity(), afterMapping(c));
  c.ambiguous = true;
  return c;
}

RelocalisationCase symmetricRoom() {
  RelocalisationCase c;
  c.description =
      "a room that a half turn about the desk maps onto itself, mapped along two opposite quarters of the loop; "
      "the second session walks within the first quarter: every view fits it and its half turn alike";
  c.scene = Scene::symmetricRoom();
  addLoop(&c.mapping, 0.0, 3.0, Eigen::Isometry3d::Identity(), 0.0);
  addLoop(&c.mapping, 6.0, 9.0, Eigen::Isometry3d::Identity(), 3.0);
  addLoop(&c.session, 1.0, 2.5, Eigen::Isometry3d::Identity(), afterMapping(c));
  c.ambiguous = true;
  return c;
}

RelocalisationCase twoDesks() {
  RelocalisationCase c;
  c.description =
      "two identical desks in one room, each mapped along 4 s of the loop round it, the furniture round the "
      "first only; the second session circles the second desk: the desk fits at either, what surrounds it "
      "only at the second";
  c.scene = Scene::twoIdenticalDesks();
  addLoop(&c.mapping, 0.0, 4.0, Eigen::Isometry3d::Identity(), 0.0);
  addLoop(&c.mapping, 0.0, 4.0, Scene::secondDesk(), 4.0);
  addLoop(&c.session, 1.0, 3.0, Scene::secondDesk(), afterMapping(c));
  return c;
}

const std::vector<std::pair<std::string, std::function<RelocalisationCase()>>>& cases() {
  static const std::vector<std::pair<std::string, std::function<RelocalisationCase()>>> all = {
      {"half-new", halfNew}, {"two-rooms", twoRooms}, {"symmetric-room", symmetricRoom}, {"two-desks", twoDesks}};
  return all;
}

}  // namespace

DepthImage RelocalisationCase::mappingView(size_t frame, const PinholeCamera& camera, const NoiseModel& noise,
                                           uint32_t seed) const {
  DepthImage view = scene.render(camera, mapping.at(frame).T_W_C, noise, seed * 100003u + frame);
  return mapping_saw_left_half_only ? withoutRightHalf(std::move(view)) : view;
}

DepthImage RelocalisationCase::sessionView(size_t frame, const PinholeCamera& camera, const NoiseModel& noise,
                                           uint32_t seed) const {
  return scene.render(camera, session.at(frame).T_W_C, noise, seed * 100003u + 50000u + frame);
}

std::vector<std::string> relocalisationCaseNames() {
  std::vector<std::string> names;
  for (const auto& [name, make] : cases()) names.push_back(name);
  return names;
}

RelocalisationCase relocalisationCase(const std::string& name) {
  std::string known;
  for (const auto& [case_name, make] : cases()) {
    if (case_name == name) {
      RelocalisationCase c = make();
      c.name = case_name;  // the table's name, the one place it is spelt
      return c;
    }
    known += (known.empty() ? "" : " | ") + case_name;
  }
  throw std::invalid_argument("no relocalisation case \"" + name + "\" (the cases: " + known + ")");
}

void writeRelocalisationCase(const std::string& directory, const RelocalisationCase& c, const PinholeCamera& camera,
                             const NoiseModel& noise, uint32_t seed) {
  // Both folders carry the whole case's ground truth, as a recording cut in two does.
  std::vector<io::StampedPose> truth = c.mapping;
  truth.insert(truth.end(), c.session.begin(), c.session.end());
  const double depth_factor = SequenceSpec().depth_factor;
  const std::string noise_words = std::string("noise ") + (noise.enabled ? "on" : "off");
  writeTumFolder(
      directory + "/mapping", "synthetic depth (sdf_tracker), relocalisation case " + c.name + ", first session, " + noise_words,
      c.mapping, truth, [&](size_t i) { return c.mappingView(i, camera, noise, seed); }, camera, depth_factor);
  writeTumFolder(
      directory + "/session", "synthetic depth (sdf_tracker), relocalisation case " + c.name + ", second session, " + noise_words,
      c.session, truth, [&](size_t i) { return c.sessionView(i, camera, noise, seed); }, camera, depth_factor);
  io::writeTextFile(directory + "/case.txt",
                    c.name + ": " + c.description + "\n" +
                        (c.ambiguous ? "ambiguous: any acceptance is false\n" : "the place can be told\n"));
}

}  // namespace sdf_tracker::synthetic
