// The node's services (save_mesh, save_volume, load_volume, save_volume_region), the mesh_blocks
// stream to a new viewer, and dynamic reconfigure of every live parameter, on the running node of
// node.test (the fixture of node_test.h).

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "node_test.h"

namespace node_test {
namespace {

TEST_F(NodeTest, SaveMeshWritesAPlyThatLoadsBack) {
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  // Three frames of its own after a reset, whatever ran before.
  for (int i = 0; i < 3; ++i) publishDeskFrame(100.0 + i, 0.0);
  sdf_tracker::SavePath save;
  save.request.path = "/tmp/sdf_tracker_node_test_mesh.ply";
  ASSERT_TRUE(callService("sdf_tracker/save_mesh", save));
  EXPECT_TRUE(save.response.success) << save.response.message;
  const st::TriangleMesh mesh = st::io::readPlyMesh(save.request.path);
  EXPECT_GT(mesh.triangles.size(), 1000u);
}

TEST_F(NodeTest, AMapSavedBySaveVolumeIsTrackedInAfterLoadVolume) {
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  for (int i = 0; i < 3; ++i) publishDeskFrame(500.0 + i / 30.0, i / 30.0);
  sdf_tracker::SavePath save;
  save.request.path = "/tmp/sdf_tracker_node_test_map.sdfmap";
  ASSERT_TRUE(callService("sdf_tracker/save_volume", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  EXPECT_GT(st::io::readSparseMap(save.request.path).blockCount(), 100u) << "the dense grid is saved as its blocks";

  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  sdf_tracker::SavePath load;
  load.request.path = save.request.path;
  ASSERT_TRUE(callService("sdf_tracker/load_volume", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  // Where the camera is in the loaded map is not known: the first frames search for it (the map's
  // start pose first) and fuse nothing; the frame that confirms the fit is tracked in the map.
  sdf_tracker::TrackingStatus in_loaded;
  int searching = 0;
  for (int i = 0; i < 6; ++i) {
    in_loaded = publishDeskFrame(510.0 + i / 30.0, 1 / 30.0);
    if (in_loaded.status != sdf_tracker::TrackingStatus::RELOCALISING) break;
    ++searching;
    EXPECT_FALSE(in_loaded.fused) << in_loaded.status_text;
  }
  EXPECT_EQ(searching, 2) << "confirmed on the third frame";
  EXPECT_EQ(in_loaded.status, sdf_tracker::TrackingStatus::OK) << in_loaded.status_text;
  EXPECT_EQ(in_loaded.status_text.find("first frame"), std::string::npos)
      << "the frame is tracked in the loaded map, not used to start a new one: " << in_loaded.status_text;

  load.request.path = "/tmp/sdf_tracker_node_test_missing.sdfmap";
  ASSERT_TRUE(callService("sdf_tracker/load_volume", load));
  EXPECT_FALSE(load.response.success);
  EXPECT_NE(load.response.message.find(load.request.path), std::string::npos) << load.response.message;
}

TEST_F(NodeTest, AnEmptyMapIsNeitherSavedNorLoaded) {
  // Issue 44: save_volume on a node that had mapped nothing answered success with a map of 0
  // blocks, and load_volume of such a file replaced the live map with one the node never tracked in.
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  sdf_tracker::SavePath save;
  save.request.path = "/tmp/sdf_tracker_node_test_empty.sdfmap";
  std::remove(save.request.path.c_str());
  ASSERT_TRUE(callService("sdf_tracker/save_volume", save));
  EXPECT_FALSE(save.response.success);
  EXPECT_NE(save.response.message.find("nothing is mapped yet"), std::string::npos) << save.response.message;
  EXPECT_FALSE(std::ifstream(save.request.path).good()) << "no file written";

  for (int i = 0; i < 3; ++i) publishDeskFrame(700.0 + i / 30.0, i / 30.0);
  st::VolumeConfig empty;
  empty.type = st::MapType::kSparse;
  st::io::writeSparseMap(save.request.path, st::SparseTsdfMap(empty));
  sdf_tracker::SavePath load;
  load.request.path = save.request.path;
  ASSERT_TRUE(callService("sdf_tracker/load_volume", load));
  EXPECT_FALSE(load.response.success);
  EXPECT_NE(load.response.message.find("an empty map"), std::string::npos) << load.response.message;
  // The live map stays: the next frame is tracked in it.
  const sdf_tracker::TrackingStatus next = publishDeskFrame(700.0 + 3 / 30.0, 3 / 30.0);
  EXPECT_EQ(next.status, sdf_tracker::TrackingStatus::OK) << next.status_text;
  EXPECT_EQ(next.status_text.find("first frame"), std::string::npos) << next.status_text;
}

TEST_F(NodeTest, SaveVolumeRegionWritesTheBoxGivenInTheMapFrame) {
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  for (int i = 0; i < 3; ++i) publishDeskFrame(600.0 + i / 30.0, i / 30.0);
  // In the map frame (REP 103: x forward, y left, z up from the first camera): 0.6 to 1.4 m ahead,
  // 0.3 m either side, 0.2 m below to 0.4 m above the camera.
  sdf_tracker::SaveRegion save;
  save.request.path = "/tmp/sdf_tracker_node_test_region.vti";
  save.request.min.x = 0.6, save.request.min.y = -0.3, save.request.min.z = -0.2;
  save.request.max.x = 1.4, save.request.max.y = 0.3, save.request.max.z = 0.4;
  ASSERT_TRUE(callService("sdf_tracker/save_volume_region", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  // The file is in the tracker's own axes (the first camera's optical frame: x right, y down,
  // z forward): the same box, within a voxel at each end.
  const st::TsdfVolume region = st::io::readVti(save.request.path);
  const st::VolumeConfig& c = region.config();
  const Eigen::Vector3d lo = c.origin_W, hi = c.origin_W + (c.dims - Eigen::Vector3i::Ones()).cast<double>() * c.voxel_size_m;
  const Eigen::Vector3d want_lo(-0.3, -0.4, 0.6), want_hi(0.3, 0.2, 1.4);
  EXPECT_LT((lo - want_lo).cwiseAbs().maxCoeff(), c.voxel_size_m + 1e-9) << lo.transpose();
  EXPECT_LT((hi - want_hi).cwiseAbs().maxCoeff(), c.voxel_size_m + 1e-9) << hi.transpose();
  EXPECT_NE(save.response.message.find(save.request.path), std::string::npos) << save.response.message;

  // A box inside out, and a file that is not a .vti: refused, saying what was given.
  std::swap(save.request.min.x, save.request.max.x);
  ASSERT_TRUE(callService("sdf_tracker/save_volume_region", save));
  EXPECT_FALSE(save.response.success);
  EXPECT_NE(save.response.message.find("min < max"), std::string::npos) << save.response.message;
  EXPECT_NE(save.response.message.find("1.4"), std::string::npos) << save.response.message;
  std::swap(save.request.min.x, save.request.max.x);
  save.request.path = "/tmp/sdf_tracker_node_test_region.ply";
  ASSERT_TRUE(callService("sdf_tracker/save_volume_region", save));
  EXPECT_FALSE(save.response.success);
  EXPECT_NE(save.response.message.find(save.request.path), std::string::npos) << save.response.message;
}

/// Collects ~mesh_blocks messages from its own subscription.
class MeshBlocksListener {
 public:
  explicit MeshBlocksListener(ros::NodeHandle& nh)
      : sub_(nh.subscribe("sdf_tracker/mesh_blocks", 10, &MeshBlocksListener::onArray, this)) {}
  /// The next message that arrives after this call (nullopt after `timeout_s`).
  std::optional<visualization_msgs::MarkerArray> next(double timeout_s = 10.0) {
    std::unique_lock<std::mutex> lock(mutex_);
    const size_t before = arrays_.size();
    if (!arrived_.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] { return arrays_.size() > before; })) {
      return std::nullopt;
    }
    return arrays_.back();
  }

 private:
  void onArray(const visualization_msgs::MarkerArray& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    arrays_.push_back(msg);
    arrived_.notify_all();
  }
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<visualization_msgs::MarkerArray> arrays_;
  ros::Subscriber sub_;
};

/// Markers that add triangles, and whether the array starts by clearing what was shown.
std::pair<size_t, bool> chunkMarkers(const visualization_msgs::MarkerArray& array) {
  size_t added = 0;
  for (const auto& marker : array.markers) added += marker.action == visualization_msgs::Marker::ADD;
  return {added, !array.markers.empty() && array.markers.front().action == visualization_msgs::Marker::DELETEALL};
}

TEST_F(NodeTest, MeshBlocksSendsANewViewerEverythingAndThenOnlyTheChunksThatChanged) {
  ASSERT_TRUE(callService("sdf_tracker/reset", *std::make_unique<std_srvs::Empty>()));
  for (int i = 0; i < 3; ++i) publishDeskFrame(700.0 + i / 30.0, i / 30.0);
  MeshBlocksListener viewer(nh_);
  ASSERT_TRUE(viewer.next()) << "nothing on ~mesh_blocks";

  // The map as blocks (whichever storage it had, an earlier test may have loaded one): the
  // viewer is told to start over and gets every chunk.
  sdf_tracker::SavePath path;
  path.request.path = "/tmp/sdf_tracker_node_test_chunks.sdfmap";
  ASSERT_TRUE(callService("sdf_tracker/save_volume", path));
  ASSERT_TRUE(callService("sdf_tracker/load_volume", path));
  ASSERT_TRUE(path.response.success) << path.response.message;
  std::optional<visualization_msgs::MarkerArray> all;
  for (int tries = 0; tries < 3 && !(all && chunkMarkers(*all).second); ++tries) all = viewer.next();
  ASSERT_TRUE(all && chunkMarkers(*all).second) << "no array starting over after the load";
  const size_t all_chunks = chunkMarkers(*all).first;
  EXPECT_GT(all_chunks, 5u);

  // A frame that measures one quadrant of the image changes part of the map: only the chunks it
  // changed are sent.
  sensor_msgs::Image patch = deskFrame(710.0, 3 / 30.0);
  {
    st::DepthImage depth = sdf_tracker_ros::toDepthImage(patch);
    for (int v = 0; v < depth.height(); ++v) {
      for (int u = 0; u < depth.width(); ++u) {
        if (u > depth.width() / 2 || v < depth.height() / 2) depth.at(u, v) = 0.0f;
      }
    }
    patch = sdf_tracker_ros::toImageMsg(depth, patch.header);
  }
  // The loaded map is searched for the camera first: two whole frames from where the patch is
  // taken fuse nothing, and the patch, the third, confirms the place and is fused.
  for (int i = 0; i < 2; ++i) {
    const auto searching = publishAndWait(deskFrame(709.9 + i / 30.0, 3 / 30.0), kQvga);
    EXPECT_EQ(searching.status, sdf_tracker::TrackingStatus::RELOCALISING) << searching.status_text;
  }
  const auto patch_status = publishAndWait(patch, kQvga);
  EXPECT_EQ(patch_status.status, sdf_tracker::TrackingStatus::OK) << patch_status.status_text;
  std::optional<visualization_msgs::MarkerArray> changed;
  for (int tries = 0; tries < 3 && !(changed && chunkMarkers(*changed).first > 0); ++tries) changed = viewer.next();
  ASSERT_TRUE(changed) << "no chunks sent after the patch was fused";
  EXPECT_FALSE(chunkMarkers(*changed).second) << "an update does not start over";
  EXPECT_GT(chunkMarkers(*changed).first, 0u);
  EXPECT_LT(chunkMarkers(*changed).first, all_chunks / 2);

  // A second viewer joins (another process: one process shares one connection per topic): it is
  // sent everything, and so, in the same message, is the first.
  ASSERT_EQ(std::system("timeout 20 rostopic echo -n 1 /sdf_tracker/mesh_blocks > /dev/null 2>&1 &"), 0);
  std::optional<visualization_msgs::MarkerArray> joined;
  for (int tries = 0; tries < 5 && !(joined && chunkMarkers(*joined).second); ++tries) joined = viewer.next();
  ASSERT_TRUE(joined && chunkMarkers(*joined).second) << "no array starting over for the new viewer";
  EXPECT_GE(chunkMarkers(*joined).first, all_chunks);
}

/// Sends one parameter through dynamic_reconfigure; returns the values the node reports in force.
std::map<std::string, st::ParameterValue> reconfigure(const std::string& name, const st::ParameterValue& value) {
  dynamic_reconfigure::Reconfigure srv;
  if (const auto* d = std::get_if<double>(&value)) {
    dynamic_reconfigure::DoubleParameter p;
    p.name = name, p.value = *d;
    srv.request.config.doubles.push_back(p);
  } else if (const auto* i = std::get_if<int>(&value)) {
    dynamic_reconfigure::IntParameter p;
    p.name = name, p.value = *i;
    srv.request.config.ints.push_back(p);
  } else if (const auto* b = std::get_if<bool>(&value)) {
    dynamic_reconfigure::BoolParameter p;
    p.name = name, p.value = *b;
    srv.request.config.bools.push_back(p);
  } else {
    dynamic_reconfigure::StrParameter p;
    p.name = name, p.value = std::get<std::string>(value);
    srv.request.config.strs.push_back(p);
  }
  std::map<std::string, st::ParameterValue> in_force;
  if (!callService("sdf_tracker/set_parameters", srv)) {
    ADD_FAILURE() << "set_parameters failed";
    return in_force;
  }
  for (const auto& p : srv.response.config.doubles) in_force[p.name] = p.value;
  for (const auto& p : srv.response.config.ints) in_force[p.name] = static_cast<int>(p.value);
  for (const auto& p : srv.response.config.bools) in_force[p.name] = static_cast<bool>(p.value);
  for (const auto& p : srv.response.config.strs) in_force[p.name] = p.value;
  return in_force;
}

/// A value other than `current` that the table accepts and that keeps `settings` valid.
std::optional<st::ParameterValue> anotherValidValue(const st::ParameterSpec& spec, const st::Settings& settings) {
  std::vector<st::ParameterValue> candidates;
  const st::ParameterValue current = spec.get(settings);
  if (const auto* b = std::get_if<bool>(&current)) candidates = {!*b};
  if (const auto* i = std::get_if<int>(&current)) candidates = {*i + 1, *i - 1};
  if (const auto* d = std::get_if<double>(&current)) candidates = {*d * 1.1, *d * 0.9, *d + 0.01, *d - 0.01};
  if (spec.name == "TrackingSchedule") candidates = {std::string("4x10,2x5,1x1")};
  for (const auto& choice : spec.choices) candidates.push_back(choice);
  for (const auto& candidate : candidates) {
    if (candidate == current) continue;
    st::Settings trial = settings;
    try {
      st::setParameter(&trial, spec.name, candidate);
    } catch (const std::invalid_argument&) {
      continue;
    }
    if (trial.validate().empty()) return candidate;
  }
  return std::nullopt;
}

TEST_F(NodeTest, EveryLiveParameterIsReconfigurableAndEveryOutOfRangeValueIsRefused) {
  // The node runs the default preset with a 160^3 grid (node.test).
  st::Settings expected = st::preset("default");
  expected.pipeline.volume.dims = Eigen::Vector3i(160, 160, 160);
  const st::Settings started_with = expected;
  std::vector<std::string> changed;
  int live = 0;
  for (const st::ParameterSpec& spec : st::parameterTable()) {
    if (!spec.live) continue;
    ++live;
    SCOPED_TRACE(spec.name);
    const st::ParameterValue before = spec.get(expected);
    if (spec.range) {  // beyond the range: refused, never clamped
      const double outside = std::isfinite(spec.range->high) && spec.range->high < 1e8 ? spec.range->high * 2 + 1
                                                                                     : spec.range->low - 1;
      const st::ParameterValue bad = spec.type == st::ParameterType::kInt ? st::ParameterValue(static_cast<int>(outside))
                                                                         : st::ParameterValue(outside);
      EXPECT_EQ(reconfigure(spec.name, bad)[spec.name], before) << "out-of-range value " << st::toText(bad);
    }
    if (spec.type == st::ParameterType::kText) {
      EXPECT_EQ(reconfigure(spec.name, std::string("not a value"))[spec.name], before);
    }
    const std::optional<st::ParameterValue> valid = anotherValidValue(spec, expected);
    ASSERT_TRUE(valid.has_value()) << "no valid alternative found to try";
    EXPECT_EQ(reconfigure(spec.name, *valid)[spec.name], *valid) << "valid value " << st::toText(*valid);
    st::setParameter(&expected, spec.name, *valid);
    changed.push_back(spec.name);
  }
  EXPECT_GT(live, 10);
  // A refused change reports what is in force in the pipeline: every accepted value is there.
  const auto in_force = reconfigure("MaxWeight", -5.0);
  for (const st::ParameterSpec& spec : st::parameterTable()) {
    if (spec.live) {
      EXPECT_EQ(in_force.at(spec.name), spec.get(expected)) << spec.name;
    }
  }
  // Every value back, last changed first (so each step is a state the loop went through): the
  // tests after this one share the node.
  for (auto name = changed.rbegin(); name != changed.rend(); ++name) {
    const st::ParameterValue value = st::findParameter(*name)->get(started_with);
    EXPECT_EQ(reconfigure(*name, value)[*name], value) << "restoring " << *name;
  }
}

}  // namespace
}  // namespace node_test
