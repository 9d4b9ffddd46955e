#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/graph/pose_graph.h"
#include "sdf_tracker/map/map_merge.h"
#include "sdf_tracker/map/tsdf_map.h"
#include "sdf_tracker/places/place_memory.h"

namespace sdf_tracker {

/// When the map is split into submaps along the path, each a sparse map over a stretch of it: what
/// loop closure moves (each submap holds the drift of its own stretch only, and a pose graph can
/// place them anew). Sparse map only.
struct SubmapConfig {
  /// A new submap starts once the camera is this far from where the active one started [m]; 0:
  /// one map for the whole path (no submaps).
  double max_distance_m = 0.0;
  /// ... or once it has turned this much from the way it looked there [degrees].
  double max_rotation_deg = 60.0;
  /// The first frames of a new submap are tracked against the one before and fused into both, so
  /// that the new one holds the view before the tracker relies on it alone.
  int handover_frames = 10;
  /// Frames are tracked against the active submap and the submaps the camera left within this much
  /// path before it started (the one before always), read as one map (merged in the background
  /// when the submap starts, overlaid on it; until the merge lands, the one before alone is
  /// overlaid): ground seen again after a short path is tracked as one map would track it, while
  /// each submap keeps only its own frames [m]. 0: the active submap alone, after the handover.
  double track_recent_m = 4.0;
  /// Where a recent submaps' voxel holds at least this weight (8 frames' at the reference noise),
  /// it alone is read, not the active submap's (OverlaidMap's settled weight): the recent ones
  /// hold that ground already. Measured (1 m submaps): against the weight cap (64), the 1 % round
  /// trip 6.37 -> 6.27 cm, the house walk 0.70 -> 0.67 cm, redkitchen 2.80 -> 2.81 cm (and, when
  /// the overlay read both maps at each sample, tracking about 1 ms a frame faster).
  double recent_settled_weight = 8.0;

  bool enabled() const { return max_distance_m > 0.0; }
  std::vector<std::string> validate() const;
};

/// Where a submap lies. Its voxels and anchor are in W, the frame the tracker worked in while it
/// was fused; the pose graph places W in the map frame (T_map_W, the identity until a loop
/// corrects it).
struct SubmapPlace {
  Eigen::Isometry3d T_W_anchor = Eigen::Isometry3d::Identity();  ///< the camera's pose when it started
  Eigen::Isometry3d T_map_W = Eigen::Isometry3d::Identity();
  int node = 0;          ///< its node in the pose graph: its index among the submaps, oldest first
  int frames_fused = 0;
  /// How far the camera had gone from the first submap's anchor to this one's, anchor to anchor
  /// [m]: the length of path between two submaps, over which drift grows.
  double path_m = 0.0;
  /// T_map_anchor: the node's pose in the graph.
  Eigen::Isometry3d T_map_anchor() const { return T_map_W * T_W_anchor; }
};

/// A stretch of the path's map that is no longer fused into.
struct Submap {
  std::unique_ptr<TsdfMap> map;
  SubmapPlace place;
};

/// The map as submaps and the pose graph between them, as a session leaves it
/// (SdfPipeline::copySubmaps) and a later session takes it up (SdfPipeline::setSubmaps): what a
/// .sdfmap keeps. A map without submaps is one submap and no edge.
struct SubmapGraph {
  /// Oldest first, the one fused into last at the end; submap i is the graph's node i.
  std::vector<Submap> submaps;
  /// The graph's edges: the odometry between consecutive submaps, the loops, and the joins of a
  /// submap started where a search found the camera (a later session's first).
  std::vector<PoseEdge> edges;
  /// The submap each keyframe of the place memory was taken in (its pose is in that submap's
  /// frame W).
  std::vector<int> keyframe_submaps;

  /// Why these cannot be a map's submaps, for a place memory of `keyframes` keyframes ("" when
  /// they can): none; a missing map; a dense grid among several; a node that is not its index; an
  /// edge from a submap to itself or to one that does not exist; a keyframe count that is not
  /// the place memory's, or a keyframe of a submap that does not exist; a submap the edges join
  /// to no other (the graph could not place it).
  std::string problem(size_t keyframes) const;
  /// `places` (of these submaps) with each keyframe in the map frame.
  std::unique_ptr<PlaceMemory> placesInMapFrame(const PlaceMemory& places) const;
  /// No submap holds an observed voxel (or there is none).
  bool observesNothing() const;
};

/// A submap as a part of a merge (mergeMaps), placed by T_target_W. Submaps are sparse maps.
PlacedMap placedSubmap(const TsdfMap& submap, const Eigen::Isometry3d& T_target_W);
/// The submaps as one map in the map frame, each where the graph places it (mergeMaps: one
/// surface where two overlap). Throws std::invalid_argument for none, or a dense grid among them.
SparseTsdfMap mergeSubmaps(const std::vector<Submap>& submaps);
/// mergeSubmaps(), but one submap at the map frame's identity is handed over as it is (a grid
/// too).
std::unique_ptr<TsdfMap> mergeSubmaps(std::vector<Submap>&& submaps);

/// `places` with each keyframe moved from its submap's frame (`keyframe_submaps`) into the map
/// frame, where T_map_W[submap] places that submap's.
std::unique_ptr<PlaceMemory> placesInMapFrame(const PlaceMemory& places, const std::vector<int>& keyframe_submaps,
                                              const std::vector<Eigen::Isometry3d>& T_map_W);

/// Whether the camera at T_W_C has left the submap started at T_W_anchor (SubmapConfig's distance
/// or turn).
bool leavesSubmap(const SubmapConfig& config, const Eigen::Isometry3d& T_W_anchor, const Eigen::Isometry3d& T_W_C);

}  // namespace sdf_tracker
