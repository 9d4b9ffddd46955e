#pragma once

#include "sdf_tracker/map/tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"

namespace sdf_tracker {

/// A wide-basin field of a map's surfaces: on a coarse lattice of `cell_m`, the (unsigned)
/// Euclidean distance from each cell to the nearest surface voxel of the map, up to `reach_m`
/// (the grid's positive truncation; cells further away hold it). The tracker, run against it,
/// pulls a pose towards the map from up to about `reach_m` away (chamfer matching), where the
/// TSDF's own basin ends at its truncation band: what a relocalisation candidate is aligned with
/// before it is refined against the map itself. The lattice covers the map's surfaces plus
/// `reach_m`; its cell grows beyond `cell_m` when that would take more than `max_cells` cells.
/// Throws std::invalid_argument when the map holds no surface.
TsdfVolume buildCoarseField(const TsdfMap& map, double cell_m, double reach_m, size_t max_cells = 16u << 20);

}  // namespace sdf_tracker
