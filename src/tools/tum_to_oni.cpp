// tum_to_oni: turns a TUM-layout depth sequence into an OpenNI 2 recording (.oni), so a depth
// camera can be replayed through OpenNI 2's own OniFile driver:
//   rosrun sdf_tracker tum_to_oni SEQUENCE_DIR OUT.oni [--frames N]
//   roslaunch sdf_tracker openni2.launch device:=OUT.oni

#include <cmath>
#include <iostream>

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/devices/oni_file.h"
#include "sdf_tracker/devices/recording.h"

namespace {

namespace st = sdf_tracker;
namespace dev = sdf_tracker::devices;

const char* kUsage = R"(usage: tum_to_oni SEQUENCE_DIR OUT.oni [--frames N]

Writes an OpenNI 2 recording of a TUM-layout depth sequence: one depth stream in millimetres
(uncompressed: about 0.6 MB per 640x480 frame), at the sequence's stamps (shifted by 1 s if they
start below 1 s, as ROS time 0 means "no time"), with the field of view of its intrinsics. The
full intrinsics go to OUT.oni.yaml, where openni2.launch finds them. OUT.oni appears only when
the recording is complete.

  --frames N   only the first N frames
)";

int run(int argc, char** argv) {
  const st::tools::CommandLine args(argc, argv, {"frames"}, {"help"}, {"SEQUENCE_DIR", "OUT.oni"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
  const st::TumSequence sequence = st::tools::openSequence(args);
  const st::PinholeCamera& camera = sequence.camera();
  const double offset_s = dev::rosStampOffset(sequence);
  dev::OniDepthWriter writer(args.positional(1), camera);
  for (size_t i = 0; i < sequence.size(); ++i) {
    writer.addFrame(static_cast<uint64_t>(std::llround((sequence.timestamp(i) + offset_s) * 1e6)),
                    sequence.depth(i).toRaw16(1000.0));
  }
  dev::writeCalibrationFile(dev::calibrationFileFor(args.positional(1)), camera, "depth");
  writer.finish();
  std::cout << "wrote " << sequence.size() << " depth frames (" << camera.width << "x" << camera.height << ") to "
            << args.positional(1);
  if (offset_s != 0.0) std::cout << " (stamps shifted by " << offset_s << " s)";
  std::cout << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return st::tools::runTool("tum_to_oni", run, argc, argv); }
