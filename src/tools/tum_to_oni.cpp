// tum_to_oni: turns a TUM-layout depth sequence into an OpenNI 2 recording (.oni), so a depth
// camera can be replayed through OpenNI 2's own OniFile driver, colour and all:
//   rosrun sdf_tracker tum_to_oni SEQUENCE_DIR OUT.oni [--frames N] [--no-colour]
//   roslaunch sdf_tracker openni2.launch device:=OUT.oni depth_registration:=true

#include <cmath>
#include <iostream>

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/devices/oni_file.h"
#include "sdf_tracker/devices/recording.h"

namespace {

namespace st = sdf_tracker;
namespace dev = sdf_tracker::devices;

const char* kUsage = R"(usage: tum_to_oni SEQUENCE_DIR OUT.oni [--frames N] [--no-colour]

Writes an OpenNI 2 recording of a TUM-layout depth sequence: a depth stream in millimetres
(uncompressed: about 0.6 MB per 640x480 frame) and, when the folder has rgb.txt, a colour stream
of the images paired with the depth frames (0.9 MB per frame), at the sequence's stamps (shifted
by 1 s if they start below 1 s, as ROS time 0 means "no time"), with the field of view of its
intrinsics. The full intrinsics go to OUT.oni.yaml (OUT.oni.rgb.yaml for colour), where
openni2.launch finds them. A TUM sequence's depth is registered to its colour: play it with
depth_registration:=true for a coloured map. OUT.oni appears only when the recording is complete.

  --frames N    only the first N frames
  --no-colour   the depth stream only
)";

int run(int argc, char** argv) {
  const st::tools::CommandLine args(argc, argv, {"frames"}, {"help", "no-colour"}, {"SEQUENCE_DIR", "OUT.oni"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
  const st::TumSequence sequence = st::tools::openSequence(args);
  const st::PinholeCamera& camera = sequence.camera();
  const double offset_s = dev::rosStampOffset(sequence);
  const bool with_colour = sequence.hasColourList() && !args.has("no-colour");
  const std::string& out = args.positional(1);
  dev::OniRecordingWriter writer(out, camera, with_colour);
  size_t colour_frames = 0;
  for (const dev::RecordedImage& image : dev::recordingOrder(sequence, with_colour)) {
    const auto timestamp_us = static_cast<uint64_t>(std::llround((image.timestamp_s + offset_s) * 1e6));
    if (image.colour) {
      writer.addColour(timestamp_us, *sequence.colour(image.frame));
      ++colour_frames;
    } else {
      writer.addDepth(timestamp_us, sequence.depth(image.frame).toRaw16(1000.0));
    }
  }
  dev::writeCalibrationFile(dev::calibrationFileFor(out), camera, "depth");
  if (with_colour) dev::writeCalibrationFile(dev::calibrationFileFor(out, dev::RecordedCamera::kColour), camera, "rgb");
  writer.finish();
  std::cout << "wrote " << sequence.size() << " depth frames";
  if (with_colour) std::cout << " and " << colour_frames << " colour images";
  std::cout << " (" << camera.width << "x" << camera.height << ") to " << out;
  if (offset_s != 0.0) std::cout << " (stamps shifted by " << offset_s << " s)";
  std::cout << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return st::tools::runTool("tum_to_oni", run, argc, argv); }
