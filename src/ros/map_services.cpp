#include "sdf_tracker/ros/map_services.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/io/mesh_file.h"
#include "sdf_tracker/io/vti_file.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/surface/surface.h"
#include "sdf_tracker/util/se3.h"

namespace sdf_tracker_ros {

namespace st = sdf_tracker;

namespace {

/// Throws std::invalid_argument naming `parameter` when `path` could not be written: its folder
/// is missing or not writable.
void requireWritableFolder(const std::string& parameter, const std::string& path) {
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  const std::string name = folder.empty() ? std::string(".") : folder.string();
  std::error_code error;
  if (!std::filesystem::is_directory(name, error)) {
    throw std::invalid_argument(parameter + " \"" + path + "\": the folder " + name + " does not exist");
  }
  if (::access(name.c_str(), W_OK) != 0) {
    throw std::invalid_argument(parameter + " \"" + path + "\": cannot write in " + name + ": " + std::strerror(errno));
  }
}

}  // namespace

MapServices::MapServices(ros::NodeHandle pnh, TrackerState& state, const NodeOptions& options, PoseBroadcaster& poses)
    : state_(state), options_(options), poses_(poses) {
  // A file that could not be written at shut-down is refused now, not after the run.
  const std::vector<std::pair<std::string, std::string>> outputs = {
      {"~trajectory_file", options_.trajectory_file}, {"~mesh_file", options_.mesh_file},
      {"~cloud_file", options_.cloud_file},
      {"~OutputTriangles (in ~output_directory)", options_.output_triangles ? outputPath("", "triangles.obj") : ""},
      {"~OutputVolume (in ~output_directory)", options_.output_volume ? outputPath("", "sdf_volume.vti") : ""}};
  for (const auto& [parameter, path] : outputs) {
    if (!path.empty()) requireWritableFolder(parameter, path);
  }
  reset_srv_ = pnh.advertiseService("reset", &MapServices::reset, this);
  relocalise_srv_ = pnh.advertiseService("relocalise", &MapServices::relocalise, this);
  save_mesh_srv_ = pnh.advertiseService("save_mesh", &MapServices::saveMesh, this);
  save_volume_srv_ = pnh.advertiseService("save_volume", &MapServices::saveVolume, this);
  save_volume_region_srv_ = pnh.advertiseService("save_volume_region", &MapServices::saveVolumeRegion, this);
  load_volume_srv_ = pnh.advertiseService("load_volume", &MapServices::loadVolume, this);
  // A node killed while writing leaves temporaries beside its files: remove them now.
  for (const std::string& path : {options_.trajectory_file, options_.mesh_file, options_.cloud_file,
                                  outputPath("", "triangles.obj"), outputPath("", "sdf_volume.vti")}) {
    if (!path.empty() && st::io::removeStaleTemporary(path)) {
      ROS_INFO("sdf_tracker: removed the unfinished %s.tmp of a run that was stopped while writing", path.c_str());
    }
  }
}

std::string MapServices::outputPath(const std::string& requested, const std::string& default_name) const {
  return requested.empty() ? options_.output_directory + "/" + default_name : requested;
}

std::vector<st::io::StampedPose> MapServices::placedTrajectory() const {
  // Where the pose graph places each pose now, in ~map_frame.
  std::vector<st::io::StampedPose> trajectory = state_.path.placed(*state_.pipeline);
  const Eigen::Isometry3d T_map_W = poses_.T_map_W();
  for (st::io::StampedPose& pose : trajectory) pose.T_W_C = T_map_W * pose.T_W_C;
  return trajectory;
}

std::unique_ptr<st::TsdfMap> MapServices::copyMap(std::vector<st::io::StampedPose>* trajectory) {
  std::lock_guard<std::mutex> lock(state_.mutex);
  if (trajectory) *trajectory = placedTrajectory();
  return state_.pipeline->copyWholeMap();  // swapped blocks (MaxMemoryMB) included
}

st::SubmapGraph MapServices::copySubmaps(std::vector<st::io::StampedPose>* trajectory, st::PlaceMemory* places) {
  std::lock_guard<std::mutex> lock(state_.mutex);
  *trajectory = placedTrajectory();
  *places = state_.pipeline->places();  // each keyframe in its submap's frame
  return state_.pipeline->copySubmaps();
}

void MapServices::writeTrajectory(const std::vector<st::io::StampedPose>& trajectory) const {
  if (options_.trajectory_file.empty()) return;
  st::io::writeTrajectory(options_.trajectory_file, trajectory);
  ROS_INFO("sdf_tracker: wrote %zu poses to %s", trajectory.size(), options_.trajectory_file.c_str());
}


bool MapServices::writeAtShutdown() {
  {
    // A pose graph solve still running lands first: the files hold the final optimised path and
    // map, as sdf_tracker_offline's do.
    std::lock_guard<std::mutex> lock(state_.mutex);
    const st::LoopReport last = state_.pipeline->finishLoopClosure();
    if (last.solved) {
      std::printf("sdf_tracker: the last pose graph solve landed at shut-down: %d loop(s) kept, %d left out\n",
                  last.closed, last.rejected);
    }
  }
  std::vector<st::io::StampedPose> trajectory;
  const std::unique_ptr<st::TsdfMap> map = copyMap(&trajectory);
  bool all_written = true;
  auto attempt = [&all_written](const char* what, const std::string& path, const std::function<void()>& write) {
    try {
      write();
      std::printf("sdf_tracker: wrote the %s to %s\n", what, path.c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "sdf_tracker: at shut-down, writing the %s failed: %s\n", what, e.what());
      all_written = false;
    }
  };
  if (!options_.trajectory_file.empty()) {
    attempt("trajectory", options_.trajectory_file,
            [&] { st::io::writeTrajectory(options_.trajectory_file, trajectory); });
  }
  const bool need_mesh = !options_.mesh_file.empty() || options_.output_triangles;
  const st::TriangleMesh mesh = need_mesh ? st::extractMesh(*map) : st::TriangleMesh();
  if (!options_.mesh_file.empty()) {
    attempt("mesh", options_.mesh_file, [&] { st::io::writePly(options_.mesh_file, mesh); });
  }
  if (!options_.cloud_file.empty()) {
    attempt("cloud", options_.cloud_file,
            [&] { st::io::writePly(options_.cloud_file, st::extractSurfaceCloud(*map)); });
  }
  if (options_.output_triangles) {
    const std::string path = outputPath("", "triangles.obj");
    attempt("triangles", path, [&] { st::io::writeObj(path, mesh); });
  }
  if (options_.output_volume) {
    const std::string path = outputPath("", "sdf_volume.vti");
    attempt("volume", path, [&] { st::io::writeMap(path, *map, nullptr, poses_.fixedMapFrame()); });
  }
  std::fflush(stdout);
  return all_written;
}

template <typename Response>
bool MapServices::answer(Response& res, const std::function<std::string()>& action) {
  try {
    res.message = action();
    res.success = true;
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
  }
  return true;  // the call itself succeeded; the response says whether the action did
}

bool MapServices::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  std::lock_guard<std::mutex> lock(state_.mutex);
  state_.pipeline->reset();
  state_.path.clear();
  state_.restarted = true;
  ROS_INFO("sdf_tracker: map and pose reset");
  return true;
}

bool MapServices::relocalise(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  return answer(res, [&] {
    std::lock_guard<std::mutex> lock(state_.mutex);
    state_.pipeline->relocalise();  // throws with Relocalise off or an empty map, saying which
    const size_t keyframes = state_.pipeline->places().keyframes().size();
    ROS_INFO("sdf_tracker: ~relocalise: searching the map for the camera");
    return "searching the map for the camera from the held pose and " + std::to_string(keyframes) +
           " keyframes; nothing is fused until a place is confirmed (see ~status)";
  });
}

bool MapServices::saveMesh(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res) {
  return answer(res, [&] {
    const std::string path = outputPath(req.path, "mesh.ply");
    std::vector<st::io::StampedPose> trajectory;
    const st::TriangleMesh mesh = st::extractMesh(*copyMap(&trajectory));
    st::io::writeMesh(path, mesh);
    writeTrajectory(trajectory);
    return "wrote " + std::to_string(mesh.triangles.size()) + " triangles to " + path;
  });
}

bool MapServices::saveVolume(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res) {
  return answer(res, [&] {
    const std::string path = outputPath(req.path, "sdf_volume.vti");
    std::vector<st::io::StampedPose> trajectory;
    st::PlaceMemory places;
    const st::SubmapGraph submaps = copySubmaps(&trajectory, &places);
    st::io::writeMap(path, submaps, &places, poses_.fixedMapFrame());
    writeTrajectory(trajectory);
    return "wrote the map to " + path +
           (st::io::hasExtension(path, ".sdfmap")
                ? " with " + std::to_string(places.keyframes().size()) + " keyframes" +
                      (submaps.submaps.size() > 1 ? " in " + std::to_string(submaps.submaps.size()) + " submaps and their pose graph" : "")
                : std::string(" (a .vti keeps no place memory)"));
  });
}

bool MapServices::saveVolumeRegion(sdf_tracker::SaveRegion::Request& req, sdf_tracker::SaveRegion::Response& res) {
  return answer(res, [&] {
    const std::string path = outputPath(req.path, "sdf_volume.vti");
    if (std::filesystem::path(path).extension() != ".vti") {
      throw std::invalid_argument("save_volume_region writes .vti files; got path \"" + path + "\"");
    }
    const Eigen::Vector3d min_map(req.min.x, req.min.y, req.min.z), max_map(req.max.x, req.max.y, req.max.z);
    if (!min_map.allFinite() || !max_map.allFinite() || !(min_map.array() < max_map.array()).all()) {
      std::ostringstream msg;
      msg << "save_volume_region needs min < max along x, y and z; got min (" << min_map.transpose() << "), max ("
          << max_map.transpose() << ")";
      throw std::invalid_argument(msg.str());
    }
    // The box along the tracker's axes that holds the one given in the map frame.
    const Eigen::AlignedBox3d box_W = st::transformedBox(poses_.T_map_W().inverse(), Eigen::AlignedBox3d(min_map, max_map));
    const st::TsdfVolume region = st::toDenseVolume(*copyMap(nullptr), box_W);
    st::io::writeVti(path, region);
    const Eigen::Vector3i dims = region.dims();
    return "wrote " + std::to_string(dims.x()) + "x" + std::to_string(dims.y()) + "x" + std::to_string(dims.z()) +
           " voxels to " + path;
  });
}

bool MapServices::loadVolume(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res) {
  return answer(res, [&] {
    const std::string path = outputPath(req.path, "sdf_volume.vti");
    bool compact;
    st::PlaceMemoryConfig places_config;
    {
      std::lock_guard<std::mutex> lock(state_.mutex);
      compact = state_.pipeline->config().volume.compact_voxels;
      places_config = state_.pipeline->config().places;
    }
    // Read before taking the lock.
    st::io::LoadedMap loaded = st::io::loadMap(path, compact, places_config);
    std::lock_guard<std::mutex> lock(state_.mutex);
    const std::string held = st::io::describeLoadedPlaces(loaded.places.get(), state_.pipeline->config().relocalise);
    const std::string submaps = st::io::describeLoadedSubmaps(loaded.submaps, state_.pipeline->config());
    const std::string grey = st::io::describeLoadedColour(*loaded.submaps.submaps.front().map,
                                                          state_.pipeline->config().fuse_colour && options_.colourUsable());
    // A grid holds no submaps: where the user left SubmapSize to the preset, one map from now on
    // (as a grid loaded at the start is); typed, setMap refuses it by name.
    st::Settings settings{state_.pipeline->config(), st::CameraSettings()};
    const bool grid = loaded.submaps.submaps.front().map->type() == st::MapType::kDense;
    const std::optional<std::string> one_map =
        grid ? settings.keepToOneMapWhereNeeded(options_.given_parameters, true) : std::nullopt;
    state_.pipeline->setSubmaps(std::move(loaded.submaps), std::move(loaded.places), one_map.has_value());
    state_.path.clear();
    state_.restarted = true;
    if (loaded.T_map_W) poses_.restoreMapFrame(*loaded.T_map_W);
    return "tracking against " + path + ", which " + held + "; " + describeLoadedMapFrame(loaded.T_map_W.has_value()) +
           (submaps.empty() ? "" : "; it " + submaps) + (grey.empty() ? "" : "; it " + grey) +
           (one_map ? "; " + *one_map : "");
  });
}

}  // namespace sdf_tracker_ros
