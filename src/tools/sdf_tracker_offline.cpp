// sdf_tracker_offline: runs the tracker over a TUM-layout depth sequence and writes the
// trajectory, the map (mesh and cloud), per-frame statistics and, when the sequence has ground
// truth, its accuracy and a plot.

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <numeric>
#include <optional>
#include <sstream>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/cli/odometry_track.h"
#include "sdf_tracker/cli/option_values.h"
#include "sdf_tracker/cli/output_folder.h"
#include "sdf_tracker/cli/report.h"
#include "sdf_tracker/cli/tracker_alone.h"
#include "sdf_tracker/eval/evaluation.h"
#include "sdf_tracker/graph/pose_graph.h"
#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/io/mesh_file.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/io/tum_sequence.h"
#include "sdf_tracker/io/vti_file.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/pipeline/tracked_path.h"
#include "sdf_tracker/surface/raycaster.h"
#include "sdf_tracker/surface/surface.h"
#include "sdf_tracker/util/frame_memory.h"
#include "sdf_tracker/util/memory.h"
#include "sdf_tracker/util/validation.h"

namespace st = sdf_tracker;

namespace {

const char* kUsage = R"(usage: sdf_tracker_offline --sequence DIR --output DIR [options]

Tracks a depth camera through a TUM-layout sequence and reconstructs the scene.

  --sequence DIR        folder with depth.txt, depth/*.png [, intrinsics.txt, groundtruth.txt,
                        rgb.txt: colour images registered to the depth, for a coloured map;
                        --param Colour=false ignores them]
  --output DIR          where trajectory.txt, mesh.ply, cloud.ply, frames.csv, summary.txt and
                        summary.json (and, with ground truth, trajectory.png; with loop closure,
                        trajectory_online.txt and loops.csv) are written; created if missing
  --preset NAME         default | paper (Table II) | reference (its launch file); default: default
  --param NAME=VALUE    override one parameter (repeatable), e.g. --param CellSize=0.02;
                        --list-params shows them all
  --frames N            only the first N frames
  --threads N           OpenMP threads (default: all cores)
  --depth-factor F      raw depth units per metre (default: intrinsics.txt, else 5000)
  --intrinsics FX,FY,CX,CY[,W,H]  override the sequence's intrinsics (no lens distortion
                        unless --distortion)
  --distortion K1,K2,P1,P2,K3  the lens distortion (plumb bob) to remove from every image;
                        0,0,0,0,0 for none (default: intrinsics.txt's last five columns,
                        else TUM's published one when the intrinsics are TUM freiburg1/2's)
  --load-volume FILE    track against a saved map instead of starting empty: a .sdfmap
                        (--save-map; loads sparse) or a .vti (--save-volume; loads dense)
  --initial-pose TX,TY,TZ,QX,QY,QZ,QW  with --load-volume: where the first camera is in the
                        loaded map (camera to map, metres and a unit quaternion); verified like
                        any relocalisation candidate before anything is fused (needs Relocalise)
  --odometry FILE       another odometry beside the tracker (a robot's wheels): the camera's poses
                        in its frame, TUM format (sdf_tracker_synth --odometry writes odometry.txt);
                        its motion predicts each frame and holds where the view constrains nothing
  --save-map            also write the map as map.sdfmap (every submap's blocks, exactly, their
                        pose graph and the place memory; --load-volume takes it up)
  --save-volume         also write the map as sdf_volume.vti (ParaView) and triangles.obj
  --volume-region X0,Y0,Z0,X1,Y1,Z1  with --save-volume: only the voxels in this box (metres,
                        the map's frame: the first camera's), e.g. one room of a large map
  --fuse-ground-truth   measure the tracker alone: track each frame from its true pose
                        (groundtruth.txt) and fuse it there, whatever the tracker found; the
                        summary gives each frame's error, free of drift (frames without a
                        ground-truth pose within 0.02 s are skipped). For exact ground truth
                        (synthetic sequences): a recording's adds its own calibration and timing
  --raycast             also ray-cast the virtual depth view every frame (as the node's
                        image_denoised) and time it
  --quiet               no progress bar, and no line as each relocalisation or loop happens
                        (frames.csv's message and the summary still say them)
  --list-params         print every parameter with its value in the chosen preset and exit
)";

/// Checks before tracking that --volume-region can be exported at the end: that it holds a grid
/// and that the grid and its write buffer fit in the memory there is now.
void requireExportable(const st::TsdfMap& map, const Eigen::AlignedBox3d& region_W, const std::string& text) {
  try {
    const st::DenseRegion region = st::denseRegionOf(map, region_W);
    const uint64_t voxels = static_cast<uint64_t>(region.dims.x()) * region.dims.y() * region.dims.z();
    std::ostringstream grid;
    grid << "--volume-region " << text << " (a grid of " << region.dims.x() << "x" << region.dims.y() << "x"
         << region.dims.z() << " voxels and its file buffer)";
    st::requireMemory(region.bytes(map.config()) + voxels * sizeof(float), grid.str());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--volume-region " + text + ": " + e.what());
  }
}

std::string joinIterations(const std::vector<int>& iterations) {
  std::string s;
  for (size_t i = 0; i < iterations.size(); ++i) s += (i ? "/" : "") + std::to_string(iterations[i]);
  return s.empty() ? "-" : s;
}


/// The process's peak resident memory so far [MiB].
double peakResidentMiB() {
  struct rusage usage;
  ::getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // Linux reports kilobytes
}

int run(int argc, char** argv) {
  const st::tools::CommandLine args(
      argc, argv,
      {"sequence", "output", "preset", "param", "frames", "threads", "depth-factor", "intrinsics", "distortion",
       "load-volume", "initial-pose", "volume-region", "odometry"},
      {"save-map", "save-volume", "fuse-ground-truth", "raycast", "quiet", "list-params", "help"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
  st::Settings settings = st::preset(args.get("preset", "default"));
  std::vector<std::string> given;
  for (const std::string& assignment : args.getAll("param")) {
    const size_t eq = assignment.find('=');
    if (eq == std::string::npos) throw std::invalid_argument("--param expects NAME=VALUE, got \"" + assignment + "\"");
    const std::string name = assignment.substr(0, eq);
    given.push_back(name);
    const st::ParameterSpec* spec = st::findParameter(name);
    if (spec && spec->readers == st::Readers::kNodeOnly) {
      throw std::invalid_argument("--param " + name + ": read by the ROS node only; the offline runner takes the "
                                  "camera from the sequence (intrinsics.txt) or from --intrinsics");
    }
    st::setParameterFromText(&settings, name, assignment.substr(eq + 1));
  }
  if (args.has("list-params")) {
    std::cout << std::left << std::setw(28) << "name" << std::setw(16) << "value" << std::setw(8) << "unit"
              << std::setw(22) << "range" << std::setw(7) << "live" << "description\n";
    for (const auto& p : st::parameterTable()) {
      if (p.readers == st::Readers::kNodeOnly) continue;
      std::string range = p.range ? p.range->toString() : "";
      for (const auto& choice : p.choices) range += (range.empty() ? "" : "|") + choice;
      std::cout << std::left << std::setw(28) << p.name << std::setw(16) << st::toText(p.get(settings)) << std::setw(8)
                << p.unit << std::setw(22) << range << std::setw(7) << (p.live ? "yes" : "no") << p.description << "\n";
    }
    return 0;
  }
  const bool loads_dense_map = st::io::readsAsDenseGrid(args.get("load-volume", ""));
  if (const auto note = settings.keepToOneMapWhereNeeded(given, loads_dense_map)) std::cout << "note: " << *note << "\n";
  st::throwIfInvalid("parameters", settings.validate());
  for (const std::string& note : settings.withoutEffect(given)) std::cerr << "warning: --param " << note << "\n";
#ifdef _OPENMP
  if (args.has("threads")) {
    // More threads than a few per core only cost memory and time (and thousands fail to start).
    const int cores = std::max(1, omp_get_num_procs());
    const int max_threads = std::max(8, 4 * cores);
    const int threads = args.getInt("threads", 0);
    if (threads < 1 || threads > max_threads) {
      throw std::invalid_argument("--threads must be in [1, " + std::to_string(max_threads) + "] on this machine (" +
                                  std::to_string(cores) + " cores; got " + args.get("threads") + ")");
    }
    omp_set_num_threads(threads);
  }
#endif

  const std::string sequence_dir = args.require("sequence");
  const std::string output_dir = args.require("output");
  if (output_dir.empty()) throw std::invalid_argument("--output must name a folder (got an empty path)");
  st::SequenceOptions options;
  if (args.has("depth-factor")) options.depth_factor = args.getDouble("depth-factor", 0.0);
  if (args.has("intrinsics")) {
    options.camera =
        st::tools::parseIntrinsics("--intrinsics", args.get("intrinsics"), st::PinholeCamera::tumFreiburg1());
  }
  if (args.has("distortion")) options.distortion = st::tools::parseDistortion("--distortion", args.get("distortion"));
  st::TumSequence sequence = st::TumSequence::open(sequence_dir, options);
  if (args.has("frames")) {
    const int frames = args.getInt("frames", 0);
    if (frames < 1) throw std::invalid_argument("--frames must be >= 1 (got " + std::to_string(frames) + ")");
    sequence.truncate(static_cast<size_t>(frames));
  }
  std::optional<Eigen::AlignedBox3d> volume_region;
  if (args.has("volume-region")) {
    if (!args.has("save-volume")) throw std::invalid_argument("--volume-region applies to --save-volume, which is not given");
    volume_region = st::tools::parseBox("--volume-region", args.get("volume-region"));
  }
  // --fuse-ground-truth: each frame's true pose in the tracker's world (the first such frame's).
  std::vector<std::optional<Eigen::Isometry3d>> true_T_W_C;
  if (args.has("fuse-ground-truth")) true_T_W_C = st::tools::truePosesInFirstFrame(sequence);
  std::optional<st::tools::OdometryTrack> odometry;
  if (args.has("odometry")) {
    odometry = st::tools::OdometryTrack::read(args.get("odometry"));
    std::vector<double> stamps(sequence.size());
    for (size_t i = 0; i < sequence.size(); ++i) stamps[i] = sequence.timestamp(i);
    const size_t covered = odometry->requireCoverage(stamps);
    if (covered < stamps.size()) {
      std::cerr << "warning: --odometry " << args.get("odometry") << " gives a pose for " << covered << " of "
                << stamps.size() << " frames; the others are predicted at constant velocity\n";
    }
    if (!odometry->jumps().empty()) std::cerr << "warning: " << odometry->jumps() << "\n";
  }
  const std::vector<std::string> summaries = {"summary.txt", "summary.json"};
  st::tools::OutputFolder output(output_dir, {"trajectory.txt", "frames.csv", "mesh.ply", "cloud.ply", "sdf_volume.vti",
                                              "map.sdfmap", "triangles.obj", "trajectory.png", "summary.txt", "summary.json",
                                              "trajectory_online.txt", "loops.csv"});
  const st::PinholeCamera& camera = sequence.camera();
  std::cout << "sequence " << sequence_dir << ": " << sequence.size() << " frames, " << camera.width << "x"
            << camera.height << ", fx " << camera.fx << " fy " << camera.fy << " cx " << camera.cx << " cy "
            << camera.cy << " (" << sequence.intrinsicsSource() << "), depth factor " << sequence.depthFactor()
            << "\n";
  std::cout << camera.distortion.summary(sequence.distortionSource()) << "\n";
  if (!sequence.distortionHint().empty()) std::cout << "note: " << sequence.distortionHint() << "\n";
  // Colour from rgb.txt (TUM's depth is registered to it), when the sequence has one and Colour is on.
  const bool read_colour = settings.pipeline.fuse_colour && sequence.hasColourList();
  if (read_colour) {
    std::cout << "colour: " << sequence.colouredFrames() << " of " << sequence.size()
              << " depth frames paired with an image of rgb.txt within " << st::TumSequence::kMaxColourGap_s * 1000.0
              << " ms (the others are fused without colour)\n";
  } else if (sequence.hasColourList()) {
    std::cout << "colour: off (Colour=false): rgb.txt is not read\n";
  }
  st::SdfPipeline pipeline(settings.pipeline);
  if (args.has("initial-pose") && !args.has("load-volume")) {
    throw std::invalid_argument("--initial-pose places the camera in a loaded map (--load-volume); a new map "
                                "starts at the first camera");
  }
  if (args.has("initial-pose") && !settings.pipeline.relocalise) {
    throw std::invalid_argument("--initial-pose is verified by the relocaliser, which --param Relocalise=false "
                                "turns off");
  }
  if (args.has("load-volume")) {
    const std::string& path = args.get("load-volume");
    st::io::LoadedMap loaded = st::io::loadMap(path, settings.pipeline.volume.compact_voxels, settings.pipeline.places);
    std::cout << (loaded.places && !loaded.places->empty() ? "" : "note: ") << path << " "
              << st::io::describeLoadedPlaces(loaded.places.get(), settings.pipeline.relocalise) << "\n";
    if (const std::string submaps = st::io::describeLoadedSubmaps(loaded.submaps, settings.pipeline); !submaps.empty()) {
      std::cout << path << " " << submaps << "\n";
    }
    if (const std::string grey = st::io::describeLoadedColour(*loaded.submaps.submaps.front().map, read_colour);
        !grey.empty()) {
      std::cout << "note: " << path << " " << grey << "\n";
    }
    pipeline.setSubmaps(std::move(loaded.submaps), std::move(loaded.places));
    // The file's grid replaces the configured one: the rules between parameters must hold for it.
    st::throwIfInvalid("parameters with the grid of " + path, st::Settings{pipeline.config(), settings.camera}.validate());
    if (args.has("initial-pose")) {
      try {
        pipeline.relocalise(st::tools::parsePose("--initial-pose", args.get("initial-pose")));
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("--initial-pose " + args.get("initial-pose") + ": " + e.what());
      }
    }
  }
  if (volume_region) requireExportable(pipeline.map(), *volume_region, args.get("volume-region"));
  const auto& v = pipeline.config().volume;
  std::cout << "preset " << args.get("preset", "default") << ": " << v.describe()
            << (args.has("load-volume") ? " (from " + args.get("load-volume") + ")" : std::string()) << ", truncation "
            << v.positive_truncation_m << " / " << pipeline.config().integrator.negative_truncation_m
            << " m, schedule " << st::formatSchedule(pipeline.config().tracker.levels) << "\n";

  std::ostringstream frames_csv;
  frames_csv << "timestamp,status,iterations,rms_residual_m,valid_points,overlap,inverse_condition,constrained_rank,"
                "tracking_ms,fusion_ms,fused,map_mb,message\n";
  st::TrackedPath path;
  // Of the frame that started each submap of this run, for loops.csv: nodes before
  // first_run_node are a loaded map's (their frames are another session's).
  std::vector<double> anchor_stamps;
  int first_run_node = args.has("load-volume") ? static_cast<int>(pipeline.submapCount()) : 0;
  std::vector<double> loop_search_ms, optimise_ms;  // frames that searched for a loop; graph solves
  std::vector<double> frame_ms, tracking_ms, fusion_ms, raycast_ms;
  size_t failed = 0, degenerate = 0;
  size_t tracked_in_map = 0;  // frames tracked against a map (not the one that started it)
  size_t unreadable = 0;      // frames whose image could not be read
  size_t swap_errors = 0;     // frames whose blocks could not be swapped (MaxMemoryMB)
  size_t coloured = 0, colour_errors = 0;  // frames fused with colour; colour images that could not be used
  std::string first_swap_error;
  std::string first_unreadable;
  st::tools::ProgressBar progress(sequence.size(), !args.has("quiet"));
  // A line of its own while the bar is drawn: the bar's line is ended first.
  const auto aside = [&progress](std::ostream& out, const std::string& line) {
    progress.finish();
    out << line << std::endl;
  };
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> single_frame_errors_m, single_frame_mahalanobis;  // --fuse-ground-truth
  std::vector<double> search_ms;              // frames spent searching for the camera (Relocalise)
  size_t relocalisations = 0, predicted_by_odometry = 0;
  size_t without_ground_truth = 0;
  for (size_t i = 0; i < sequence.size(); ++i) {
    if (!true_T_W_C.empty() && !true_T_W_C[i]) {
      ++without_ground_truth;
      continue;
    }
    std::optional<st::DepthImage> read;
    try {
      read = sequence.depth(i);
    } catch (const std::runtime_error& e) {
      // As the node does with a bad image: this frame is bad input, the run goes on.
      std::string message = e.what();
      aside(std::cerr, "frame " + std::to_string(i) + ": " + message + ": skipped");
      if (unreadable++ == 0) first_unreadable = message;
      ++failed;
      std::replace(message.begin(), message.end(), ',', ';');
      frames_csv << std::fixed << std::setprecision(6) << sequence.timestamp(i) << ','
                 << st::toString(st::TrackStatus::kBadInput) << ",,0,0,0,0,0,0,0,0," << std::setprecision(3)
                 << pipeline.mapMemoryBytes() / 1048576.0 << ',' << message << '\n';
      progress.update(i + 1);
      continue;
    }
    const st::DepthImage& depth = *read;
    std::optional<st::ColourImage> colour;
    if (read_colour) {
      try {
        colour = sequence.colour(i);
      } catch (const std::runtime_error& e) {
        // The depth is tracked and fused all the same, without colour; said once, counted.
        if (colour_errors++ == 0)
          aside(std::cerr, "frame " + std::to_string(i) + ": " + e.what() + ": fused without colour");
      }
    }
    const st::ColourImage* colour_in = colour ? &*colour : nullptr;
    const std::optional<Eigen::Isometry3d> T_odom_C =
        odometry ? odometry->at(sequence.timestamp(i)) : std::optional<Eigen::Isometry3d>();
    const st::FrameReport report =
        true_T_W_C.empty()
            ? pipeline.processFrame(depth, camera, sequence.timestamp(i), T_odom_C, colour_in)
            : pipeline.processFrameAtPose(depth, camera, *true_T_W_C[i], sequence.timestamp(i), colour_in);
    coloured += report.coloured;
    predicted_by_odometry += report.predicted_by_odometry;
    const st::TrackResult& t = report.track;
    if (report.relocalisation.searched) {
      search_ms.push_back(report.relocalisation.search_ms);
      if (report.relocalisation.outcome == st::Relocaliser::Outcome::kAccepted) {
        ++relocalisations;
        if (!args.has("quiet")) {
          std::cout << "\nframe " << i << ": relocalised after " << report.relocalisation.frames_spent << " frames\n";
        }
      }
    }
    if (!t.tracked()) ++failed;
    if (t.tracked() && t.status == st::TrackStatus::kDegenerate) ++degenerate;
    if (t.tracked() && !report.initialised_map) ++tracked_in_map;
    // Estimates only (a held pose is none; frames.csv lists every frame): with --fuse-ground-truth,
    // where the tracker took the frame, not the fused pose.
    if (report.reset) {
      path.detachFromSubmaps();
    }
    if (report.initialised_map) {
      anchor_stamps.clear();
      first_run_node = 0;
    }
    if (report.initialised_map || report.started_submap) anchor_stamps.push_back(sequence.timestamp(i));
    if (t.tracked()) {
      const Eigen::Isometry3d T_W_C = true_T_W_C.empty() ? pipeline.pose() : t.T_W_C;
      path.add(sequence.timestamp(i), report.submap, T_W_C, pipeline.submapPlace(report.submap).T_map_W * T_W_C);
    }
    if (report.loop.searched) loop_search_ms.push_back(report.loop.search_ms);
    // Said as it happens (unless --quiet) and in frames.csv's message.
    std::vector<std::string> loop_events;
    if (report.loop.found) {
      loop_events.push_back("loop found: the view of submap " + std::to_string(report.loop.frame_submap) +
                            " is in submap " + std::to_string(report.loop.submap));
    }
    if (report.loop.solved) {
      optimise_ms.push_back(report.loop.optimise_ms);
      std::ostringstream solved;
      solved << "pose graph solved, " << report.loop.closed << " loop(s) closed, " << report.loop.rejected
             << " rejected; the active submap moved " << std::setprecision(3) << report.loop.correction_m * 100.0
             << " cm, " << report.loop.correction_deg << " deg";
      loop_events.push_back(solved.str());
    }
    if (!args.has("quiet")) {
      for (const std::string& event : loop_events) aside(std::cout, "frame " + std::to_string(i) + ": " + event);
    }
    if (!true_T_W_C.empty() && !report.initialised_map && t.tracked()) {
      const Eigen::Vector3d error_m = t.T_W_C.translation() - true_T_W_C[i]->translation();
      single_frame_errors_m.push_back(error_m.norm());
      single_frame_mahalanobis.push_back(st::tools::squaredMahalanobisOfPosition(error_m, t.covariance));
    }
    double cast_ms = 0.0;
    if (args.has("raycast")) {
      const auto cast_start = std::chrono::steady_clock::now();
      st::raycast(pipeline.map(), camera, pipeline.pose(), settings.pipeline.raycast, &depth);
      cast_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - cast_start).count();
      raycast_ms.push_back(cast_ms);
    }
    if (!report.initialised_map) {
      tracking_ms.push_back(report.tracking_ms);
      if (report.fused) fusion_ms.push_back(report.fusion_ms);
      frame_ms.push_back(report.tracking_ms + report.fusion_ms + cast_ms);
    }
    if (!report.swap_notice.empty()) aside(std::cout, report.swap_notice);
    if (!report.swap_warning.empty())
      aside(std::cerr, "frame " + std::to_string(i) + ": warning: " + report.swap_warning);
    std::string message = t.message;
    const auto say = [&message](const std::string& text) { message += (message.empty() ? "" : "; ") + text; };
    if (report.loop.searched && !report.loop.message.empty()) {
      say("loop search in submap " + std::to_string(report.loop.submap) + ": " + report.loop.message);
    }
    for (const std::string& event : loop_events) say(event);
    if (!report.swap_error.empty()) {
      // Said once as it happens (every frame after it may fail alike); each frame's is in frames.csv.
      if (swap_errors++ == 0) {
        first_swap_error = report.swap_error;
        aside(std::cerr, "frame " + std::to_string(i) + ": " + report.swap_error + " (later swap errors: frames.csv)");
      }
      say(report.swap_error);
    }
    std::replace(message.begin(), message.end(), ',', ';');
    frames_csv << std::fixed << std::setprecision(6) << sequence.timestamp(i) << ',' << st::toString(t.status) << ','
               << joinIterations(t.iterations_per_level) << ',' << std::setprecision(6) << t.rms_residual_m << ','
               << t.valid_points << ',' << std::setprecision(3) << t.overlap << ',' << std::setprecision(6)
               << t.inverse_condition << ',' << t.constrained_rank
               << ',' << std::setprecision(3) << report.tracking_ms << ',' << report.fusion_ms << ','
               << (report.fused ? 1 : 0) << ',' << pipeline.mapMemoryBytes() / 1048576.0 << ',' << message << '\n';
    progress.update(i + 1);
  }
  progress.finish();
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Apart from the peak of the whole run: the mesh, cloud and saved map below read the whole map
  // at once (beyond MaxMemoryMB, which bounds the map while tracking).
  const double tracking_rss_mb = peakResidentMiB();

  if (pipeline.config().loops.enabled) {
    // trajectory.txt is the final one: every pose where the optimised graph places its submap,
    // once the last solve has landed.
    const st::LoopReport last = pipeline.finishLoopClosure();
    if (last.searched) loop_search_ms.push_back(last.search_ms);
    if (last.solved) optimise_ms.push_back(last.optimise_ms);
    st::io::writeTrajectory(output.path("trajectory_online.txt"), path.published());
    // Each loop as the submaps' anchors it joins (the frames that started them), to hold against
    // a ground truth.
    std::ostringstream loops_csv;
    loops_csv << "from_submap,to_submap,from_anchor_time,to_anchor_time,tx,ty,tz,qx,qy,qz,qw,kept,sigma_m,sigma_deg\n"
              << std::fixed;
    for (const st::SdfPipeline::Loop& loop : pipeline.loops()) {
      const st::PoseEdge& e = loop.edge;
      const Eigen::Quaterniond q(e.T_from_to.rotation());
      const Eigen::Vector3d t = e.T_from_to.translation();
      auto stamp = [&](int node) {  // empty for a loaded map's submap
        const int index = node - first_run_node;
        if (index < 0 || index >= static_cast<int>(anchor_stamps.size())) return std::string();
        std::ostringstream text;
        text << std::fixed << std::setprecision(6) << anchor_stamps[index];
        return text.str();
      };
      loops_csv << e.from << ',' << e.to << ',' << stamp(e.from) << ',' << stamp(e.to) << ',' << std::setprecision(7)
                << t.x() << ',' << t.y() << ',' << t.z() << ',' << q.x() << ',' << q.y() << ',' << q.z() << ','
                << q.w() << ',' << (loop.kept ? 1 : 0) << ',';
      // How firmly it holds: its least certain direction (a corridor's length: about a kilometre).
      const st::PoseSigma sigma = st::leastCertainSigma(e.information);
      loops_csv << std::setprecision(4) << sigma.m << ',' << sigma.deg << '\n';
    }
    st::io::writeTextFile(output.path("loops.csv"), loops_csv.str());
  }
  const std::vector<st::io::StampedPose> trajectory = path.placed(pipeline);
  st::io::writeTrajectory(output.path("trajectory.txt"), trajectory);
  st::io::writeTextFile(output.path("frames.csv"), frames_csv.str());
  pipeline.withWholeMap([&](const st::TsdfMap& map) {  // swapped blocks included
    const st::TriangleMesh mesh = st::extractMesh(map);
    st::io::writePly(output.path("mesh.ply"), mesh);
    st::io::writePly(output.path("cloud.ply"), st::extractSurfaceCloud(map));
    if (args.has("save-volume")) {
      if (volume_region) st::io::writeVti(output.path("sdf_volume.vti"), st::toDenseVolume(map, *volume_region));
      else st::io::writeMap(output.path("sdf_volume.vti"), map);
      st::io::writeObj(output.path("triangles.obj"), mesh);
    }
  });

  // The submaps, their graph and place memory, as a second session takes them up.
  if (args.has("save-map")) st::io::writeMap(output.path("map.sdfmap"), pipeline.copySubmaps(), &pipeline.places());

  const double peak_rss_mb = peakResidentMiB();

  // A run fails when no frame was tracked against a map: one the first frame started, or a loaded
  // one (then the first frame is tracked in it too). A single frame starting a map is no failure.
  const bool nothing_tracked = tracked_in_map == 0 && (sequence.size() > 1 || args.has("load-volume"));
  std::ostringstream summary;
  summary << std::fixed << std::setprecision(2);
  const size_t processed = sequence.size() - without_ground_truth;
  summary << "frames " << sequence.size() << ", tracked ok " << processed - failed - degenerate;
  if (degenerate > 0) summary << ", degenerate " << degenerate << " (solved where the geometry constrains the pose)";
  summary << ", failed " << failed << "\n";
  if (unreadable > 0) {
    summary << unreadable << " frame" << (unreadable > 1 ? "s" : "") << " could not be read and counted as failed "
            << "(bad_input), the first: " << first_unreadable << "\n";
  }
  summary << "speed " << sequence.size() / elapsed_s << " frames/s including file reading; per frame (ms): median "
          << st::evaluation::percentile(frame_ms, 0.5) << ", p95 " << st::evaluation::percentile(frame_ms, 0.95) << "; tracking median "
          << st::evaluation::percentile(tracking_ms, 0.5) << ", fusion median " << st::evaluation::percentile(fusion_ms, 0.5);
  if (!raycast_ms.empty()) summary << ", ray casting median " << st::evaluation::percentile(raycast_ms, 0.5);
  if (!search_ms.empty()) {
    summary << "\nrelocalisation: " << search_ms.size() << " frames searched the map for the camera (ms per frame: "
            << "median " << st::evaluation::percentile(search_ms, 0.5) << ", max " << st::evaluation::percentile(search_ms, 1.0) << "), "
            << relocalisations << " found it";
  }
  if (odometry) {
    summary << "\nodometry: " << predicted_by_odometry << " frames predicted from " << args.get("odometry");
  }
  if (read_colour) {
    summary << "\ncolour: " << coloured << " frames fused with colour";
    if (colour_errors > 0) {
      summary << ", " << colour_errors << (colour_errors == 1 ? " colour image" : " colour images")
              << " could not be used (see above)";
    }
  }
  summary << "\nplace memory: " << pipeline.places().keyframes().size() << " keyframes, "
          << pipeline.places().bytesPerKeyframe() << " bytes each";
  if (pipeline.config().submaps.enabled()) {
    summary << "\nsubmaps: " << pipeline.submapCount() << " (SubmapSize " << pipeline.config().submaps.max_distance_m
            << " m, SubmapTurn " << pipeline.config().submaps.max_rotation_deg << " deg), merged into one for the mesh and cloud"
            << (args.has("save-map") ? "; map.sdfmap keeps them and their pose graph" : "");
  }
  if (pipeline.config().loops.enabled) {
    summary << "\nloops: " << pipeline.loopsClosed() << " closed, " << pipeline.loopsRejected()
            << " rejected by the pose graph; " << loop_search_ms.size() << " frames searched for one";
    if (!loop_search_ms.empty()) {
      summary << " (off the tracking thread; ms per frame: median " << st::evaluation::percentile(loop_search_ms, 0.5)
              << ", max " << st::evaluation::percentile(loop_search_ms, 1.0) << ")";
    }
    if (optimise_ms.empty()) {
      summary << "; the graph was never solved (no loop): trajectory.txt is the path as published";
    } else {
      summary << "; graph solved " << optimise_ms.size() << (optimise_ms.size() == 1 ? " time" : " times")
              << " (off the tracking thread) in " << st::evaluation::percentile(optimise_ms, 0.5) << " ms (median), "
              << st::evaluation::percentile(optimise_ms, 1.0) << " ms (max); trajectory.txt is the optimised path, "
              << "trajectory_online.txt the one published at the time";
    }
  }
  summary << "\nmemory: " << st::toString(v.type) << " map " << pipeline.mapMemoryBytes() / 1048576.0 << " MiB";
  if (const st::MapMemoryBudget* budget = pipeline.memoryBudget()) {
    summary << " (MaxMemoryMB " << pipeline.config().max_map_memory_mb << "; " << budget->swap().size()
            << " blocks, " << budget->swap().bytesOnDisk() / 1048576.0 << " MiB, in the swap file at the end)";
  } else if (const st::SubmapStore& closed = pipeline.closedSubmaps(); closed.swaps()) {
    summary << " (MaxMemoryMB " << pipeline.config().max_map_memory_mb << "; " << closed.swappedCount() << " of "
            << pipeline.submapCount() << " submaps, " << closed.bytesOnDisk() / 1048576.0
            << " MiB, in the swap file at the end)";
  }
  summary << ", peak resident " << peak_rss_mb << " MiB (" << tracking_rss_mb << " MiB while tracking)\n";
  if (swap_errors > 0) {
    summary << "swap file failed on " << swap_errors << " frame" << (swap_errors > 1 ? "s" : "")
            << ", blocks kept in memory (the map ended at " << pipeline.mapMemoryBytes() / 1048576.0
            << " MiB against MaxMemoryMB " << pipeline.config().max_map_memory_mb << "); the first: "
            << first_swap_error << "\n";
  }

  // The same figures for scripts (bench/), as JSON.
  using st::tools::jsonNumber;
  using st::tools::jsonString;
  std::ostringstream json;
  json << "{\n  \"sequence\": " << jsonString(sequence_dir) << ",\n  \"preset\": "
       << jsonString(args.get("preset", "default")) << ",\n  \"frames\": " << sequence.size()
       << ",\n  \"failed_frames\": " << failed << ",\n  \"degenerate_frames\": " << degenerate
       << ",\n  \"map_type\": " << jsonString(st::toString(v.type));
  if (v.type == st::MapType::kDense) json << ",\n  \"grid\": [" << v.dims.x() << ", " << v.dims.y() << ", " << v.dims.z() << "]";
  json << ",\n  \"voxel_count\": " << pipeline.map().voxelCount()
       << ",\n  \"voxel_size_m\": " << jsonNumber(v.voxel_size_m)
       << ",\n  \"compact_voxels\": " << (v.compact_voxels ? "true" : "false")
       << ",\n  \"coloured_frames\": " << coloured
#ifdef _OPENMP
       << ",\n  \"threads\": " << omp_get_max_threads()
#endif
       << ",\n  \"ms\": {";
  const std::vector<std::pair<const char*, const std::vector<double>*>> stages = {
      {"frame", &frame_ms}, {"tracking", &tracking_ms}, {"fusion", &fusion_ms}, {"raycast", &raycast_ms}};
  for (size_t i = 0; i < stages.size(); ++i) {
    json << (i ? ", " : "") << "\"" << stages[i].first << "_median\": " << jsonNumber(st::evaluation::percentile(*stages[i].second, 0.5))
         << ", \"" << stages[i].first << "_p95\": " << jsonNumber(st::evaluation::percentile(*stages[i].second, 0.95));
  }
  json << "},\n  \"peak_rss_mb\": " << jsonNumber(peak_rss_mb)
       << ",\n  \"peak_rss_tracking_mb\": " << jsonNumber(tracking_rss_mb)
       << ",\n  \"grid_mb\": " << jsonNumber(pipeline.mapMemoryBytes() / 1048576.0)
       << ",\n  \"submaps\": " << pipeline.submapCount() << ",\n  \"loops_closed\": " << pipeline.loopsClosed()
       << ",\n  \"loops_rejected\": " << pipeline.loopsRejected() << ",\n  \"loop_search\": {\"searched_frames\": "
       << loop_search_ms.size() << ", \"ms_median\": " << jsonNumber(st::evaluation::percentile(loop_search_ms, 0.5))
       << ", \"ms_max\": " << jsonNumber(st::evaluation::percentile(loop_search_ms, 1.0))
       << "},\n  \"graph_solve\": {\"solves\": " << optimise_ms.size()
       << ", \"ms_median\": " << jsonNumber(st::evaluation::percentile(optimise_ms, 0.5))
       << ", \"ms_max\": " << jsonNumber(st::evaluation::percentile(optimise_ms, 1.0)) << "}"
       << ",\n  \"swapped_mb\": "
       << jsonNumber((pipeline.memoryBudget() ? pipeline.memoryBudget()->swap().bytesOnDisk()
                                              : pipeline.closedSubmaps().bytesOnDisk()) /
                     1048576.0)
       << ",\n  \"elapsed_s\": " << jsonNumber(elapsed_s)
       << ",\n  \"relocalisation\": {\"searched_frames\": " << search_ms.size() << ", \"found\": " << relocalisations
       << ", \"ms_median\": " << jsonNumber(st::evaluation::percentile(search_ms, 0.5))
       << ", \"ms_max\": " << jsonNumber(st::evaluation::percentile(search_ms, 1.0))
       << ", \"keyframes\": " << pipeline.places().keyframes().size() << "}";
  if (!true_T_W_C.empty()) {
    const st::tools::SingleFrameErrors errors(single_frame_errors_m, single_frame_mahalanobis);
    summary << errors.summaryLine(without_ground_truth);
    if (errors.stats.count > 0) json << ",\n  \"single_frame_error_m\": " << errors.json();
  }
  if (nothing_tracked) {
    summary << "no frame could be tracked" << (args.has("load-volume") ? " in the loaded map" : " after the first")
            << ": accuracy not evaluated\n";
  } else if (!sequence.groundTruth().empty()) {
    try {
      const auto accuracy = st::tools::evaluateAccuracy(trajectory, sequence.groundTruth());
      summary << st::tools::formatAccuracy(accuracy);
      st::tools::writeAccuracyPlot(output.path("trajectory.png"), accuracy, "sdf_tracker on " + sequence_dir);
      const auto& ate = accuracy.ate.translation_m;
      json << ",\n  \"ate_m\": {\"rmse\": " << jsonNumber(ate.rmse) << ", \"mean\": " << jsonNumber(ate.mean)
           << ", \"median\": " << jsonNumber(ate.median) << ", \"max\": " << jsonNumber(ate.max) << "}";
      if (accuracy.rpe.translation_m_per_s.count > 0) {
        json << ",\n  \"rpe\": {\"m_per_s\": " << jsonNumber(accuracy.rpe.translation_m_per_s.rmse)
             << ", \"deg_per_s\": " << jsonNumber(accuracy.rpe.rotation_deg_per_s.rmse) << "}";
      }
    } catch (const std::invalid_argument& e) {  // too few poses to align
      summary << "accuracy not evaluated: " << e.what() << "\n";
    }
  } else {
    summary << "no groundtruth.txt: accuracy not evaluated\n";
  }
  json << "\n}\n";
  st::io::writeTextFile(output.path("summary.txt"), summary.str());
  st::io::writeTextFile(output.path("summary.json"), json.str());
  output.commit(summaries);
  std::cout << summary.str() << "results in " << output_dir << "\n";
  return nothing_tracked ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  sdf_tracker::keepFrameMemoryResident();
  return sdf_tracker::tools::runTool("sdf_tracker_offline", run, argc, argv);
}
