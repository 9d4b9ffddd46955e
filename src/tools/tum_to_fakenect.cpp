// tum_to_fakenect: turns a TUM-layout depth sequence into a libfreenect "fakenect" recording, so a
// Kinect v1 can be replayed through libfreenect itself, colour and all:
//   rosrun sdf_tracker tum_to_fakenect SEQUENCE_DIR DUMP_DIR [--frames N] [--no-colour]
//   roslaunch sdf_tracker kinect.launch fakenect:=DUMP_DIR depth_registration:=true

#include <cmath>
#include <iostream>

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/devices/fakenect_dump.h"
#include "sdf_tracker/devices/kinect_disparity.h"
#include "sdf_tracker/devices/recording.h"

namespace {

namespace st = sdf_tracker;
namespace dev = sdf_tracker::devices;

const char* kUsage = R"(usage: tum_to_fakenect SEQUENCE_DIR DUMP_DIR [--frames N] [--no-colour]

Writes a fakenect recording (libfreenect's replay format: INDEX.txt and one PGM per frame) of a
640x480 TUM-layout depth sequence: each depth becomes the raw 11-bit disparity a Kinect v1 sends
for it (libfreenect's depth model with typical Kinect v1 zero-plane values), at the sequence's stamps
(shifted by 1 s if they start below 1 s, as ROS time 0 means "no time"), and, when the folder has
rgb.txt, the colour images paired with the depth frames, at their own stamps. The sequence's
intrinsics go to DUMP_DIR/depth_camera_info.yaml (and rgb_camera_info.yaml), where kinect.launch
finds them. A TUM sequence's depth is registered to its colour: play it with
depth_registration:=true for a coloured map. DUMP_DIR must not exist; it appears only when the
recording is complete.

  --frames N    only the first N frames
  --no-colour   depth frames only
)";

int run(int argc, char** argv) {
  const st::tools::CommandLine args(argc, argv, {"frames"}, {"help", "no-colour"}, {"SEQUENCE_DIR", "DUMP_DIR"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
  const st::TumSequence sequence = st::tools::openSequence(args);
  const st::PinholeCamera& camera = sequence.camera();
  if (camera.width != dev::fakenect::kWidth || camera.height != dev::fakenect::kHeight) {
    throw std::invalid_argument("fakenect replays 640x480 depth only; " + args.positional(0) + " is " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  const double offset_s = dev::rosStampOffset(sequence);
  const dev::KinectDisparityTable table;
  dev::FakenectDumpWriter writer(args.positional(1));
  const bool with_colour = sequence.hasColourList() && !args.has("no-colour");
  size_t out_of_range = 0, measured = 0, colour_frames = 0;
  std::vector<uint16_t> disparities;
  for (const dev::RecordedImage& image : dev::recordingOrder(sequence, with_colour)) {
    if (image.colour) {
      writer.addColour(image.timestamp_s + offset_s, *sequence.colour(image.frame));
      ++colour_frames;
      continue;
    }
    disparities = sequence.depth(image.frame).toRaw16(1000.0);  // millimetres, then what a Kinect sends for them
    for (uint16_t& value : disparities) {
      if (value == 0) {
        value = dev::kKinectNoDisparity;
        continue;
      }
      ++measured;
      value = table.fromMillimetres(value);
      if (value == dev::kKinectNoDisparity) ++out_of_range;
    }
    writer.addDepth(image.timestamp_s + offset_s, disparities);
  }
  dev::writeCalibrationFile(dev::calibrationFileFor(writer.stagingFolder()), camera, "depth");
  if (with_colour) {
    dev::writeCalibrationFile(dev::calibrationFileFor(writer.stagingFolder(), dev::RecordedCamera::kColour), camera,
                              "rgb");
  }
  writer.finish();
  std::cout << "wrote " << sequence.size() << " depth frames";
  if (with_colour) std::cout << " and " << colour_frames << " colour images";
  std::cout << " to " << args.positional(1);
  if (offset_s != 0.0) std::cout << " (stamps shifted by " << offset_s << " s)";
  std::cout << "\n";
  if (out_of_range > 0) {
    std::cout << out_of_range << " of " << measured << " depths lie outside what a Kinect reports ("
              << table.nearest_mm() << "-" << table.farthest_mm() << " mm) and were recorded as no data\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return st::tools::runTool("tum_to_fakenect", run, argc, argv); }
