// sdf_tracker_synth: writes a synthetic depth sequence with exact ground truth in TUM layout.

#include <iostream>

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/sim/relocalisation_cases.h"
#include "sdf_tracker/sim/synthetic.h"

namespace {

const char* kUsage = R"(usage: sdf_tracker_synth --output DIR [options]

Renders an analytic indoor scene along a scripted camera path, in TUM layout
(depth.txt, depth/*.png, groundtruth.txt, intrinsics.txt).

  --output DIR       folder to write (created)
  --motion NAME      desk (default) | slow | fast | planar | loop | walk (through a house, 0.5 m/s)
                     | corridor (a robot down the house's corridor and back at 0.5 m/s, its camera
                     0.4 m high looking 50 degrees to the side) | round-trip (a walk at 0.5 m/s down
                     the corridor, round two rooms and back to where it started, looking the same
                     way: about 37 m, 75 s)
  --bare-walls       walk, corridor and round-trip: bare walls, but for six pictures in the
                     corridor (default: a picture or a shelf every metre of every wall); close to a
                     bare wall the view holds one plane, which depth alone cannot place
  --frames N         number of frames (default 300, at 30 Hz)
  --seed N           noise seed (default 1)
  --size WxH         image size: 640x480 (default), 320x240 or 160x120 (freiburg1 intrinsics, scaled)
  --no-noise         exact depth, no Kinect-like noise, dropouts or quantisation
  --disparity-subpixels N   disparity quantisation steps per pixel (default 8; 0 = none)
  --noise-scale S    scale of the axial Gaussian noise (default 1)
  --depth-bias B     a depth error fixed in the image, as an uncalibrated Kinect's: depth B times
                     too long at the corners (B < 0: too short), growing with the square of the
                     distance from the principal point; in [-0.1, 0.1], default 0; applies with
                     --no-noise too
  --colour           also write rgb/ and rgb.txt: colour images registered to the depth (the
                     scenes' surfaces in tiles of 0.25 m, six colours), at the depth's timestamps
  --odometry         also write odometry.txt: the camera's poses as a robot's wheel odometry would
                     report them (each metre 2 % too long, the heading drifting 1 degree per metre,
                     noise), for sdf_tracker_offline --odometry
  --relocalisation-case NAME   instead of one sequence, a second session in a saved map:
                     DIR/mapping (map it at its true poses: sdf_tracker_offline --fuse-ground-truth
                     --save-map) and DIR/session (run it in that map: --load-volume), at 15 Hz;
                     NAME: half-new | two-rooms | symmetric-room | two-desks (DIR/case.txt says
                     what each is). --size, --seed and the noise options apply
)";

int run(int argc, char** argv) {
  using namespace sdf_tracker;
  const tools::CommandLine args(argc, argv,
                                {"output", "motion", "frames", "seed", "size", "disparity-subpixels", "noise-scale",
                                 "depth-bias", "relocalisation-case"},
                                {"no-noise", "bare-walls", "odometry", "colour", "help"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
  synthetic::SequenceSpec spec;
  spec.motion = synthetic::parseMotion(args.get("motion", "desk"));
  spec.frames = args.getInt("frames", 300);
  spec.seed = static_cast<uint32_t>(args.getInt("seed", 1));
  if (args.has("bare-walls")) {
    if (!synthetic::goesThroughTheHouse(spec.motion)) {
      throw std::invalid_argument(
          "--bare-walls: only the walk, the corridor and the round trip go through the house (got --motion " +
          synthetic::toString(spec.motion) + ")");
    }
    spec.house_walls = synthetic::HouseWalls::kBare;
  }
  if (args.has("size")) {
    const std::string size = args.get("size");
    const size_t x = size.find('x');
    if (x == std::string::npos) throw std::invalid_argument("--size: expected WxH like 320x240, got \"" + size + "\"");
    spec.camera = PinholeCamera::tumFreiburg1().scaledTo(parseInteger("--size", size.substr(0, x)),
                                                         parseInteger("--size", size.substr(x + 1)));
  }
  spec.colour = args.has("colour");
  if (args.has("odometry")) {
    spec.odometry = synthetic::WheelOdometryModel{};
    spec.odometry->seed = spec.seed;
  }
  spec.noise.enabled = !args.has("no-noise");
  spec.noise.disparity_subpixels = args.getInt("disparity-subpixels", spec.noise.disparity_subpixels);
  spec.noise.axial_noise_scale = args.getDouble("noise-scale", spec.noise.axial_noise_scale);
  spec.noise.depth_bias = args.getDouble("depth-bias", spec.noise.depth_bias);
  synthetic::checkDepthBias(spec.noise.depth_bias, "--depth-bias");
  const std::string noise_words = std::string("noise ") + (spec.noise.enabled ? "on" : "off") +
                                  (spec.noise.depth_bias != 0.0 ? ", depth bias " + args.get("depth-bias") : "");
  const std::string output = args.require("output");
  if (args.has("relocalisation-case")) {
    for (const char* option : {"motion", "frames", "bare-walls", "odometry", "colour"}) {
      if (args.has(option)) {
        throw std::invalid_argument(std::string("--") + option + ": a relocalisation case has its own paths (got --relocalisation-case " +
                                    args.get("relocalisation-case") + ")");
      }
    }
    const synthetic::RelocalisationCase c = synthetic::relocalisationCase(args.get("relocalisation-case"));
    synthetic::writeRelocalisationCase(output, c, spec.camera, spec.noise, spec.seed);
    std::cout << "wrote relocalisation case " << c.name << " (" << c.mapping.size() << " frames to map, "
              << c.session.size() << " in the second session, " << noise_words << ") to " << output << "\n";
    return 0;
  }
  synthetic::writeSequence(output, spec);
  std::cout << "wrote " << spec.frames << " frames (" << synthetic::toString(spec.motion) << ", " << noise_words
            << ") to " << output << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return sdf_tracker::tools::runTool("sdf_tracker_synth", run, argc, argv); }
