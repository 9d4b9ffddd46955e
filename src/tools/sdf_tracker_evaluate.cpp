// sdf_tracker_evaluate: ATE and RPE of a TUM trajectory against ground truth, with a plot; or how
// well a coloured mesh agrees with the colour images it was made from.

#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/cli/report.h"
#include "sdf_tracker/eval/colour_agreement.h"
#include "sdf_tracker/eval/evaluation.h"
#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/mesh_file.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/io/tum_sequence.h"

namespace {

const char* kUsage = R"(usage: sdf_tracker_evaluate --groundtruth FILE --estimate FILE [--plot FILE.png]
                            [--errors FILE.csv] [--estimate-time-offset S] [--map-frame-from FILE]
       sdf_tracker_evaluate --mesh FILE.ply --sequence DIR --estimate FILE [--frame-step N]

Absolute trajectory error (rigid alignment) and relative pose error (1 s window), as defined by
the TUM RGB-D benchmark; timestamps are associated within 0.02 s. --estimate-time-offset S is
subtracted from the estimate's timestamps first (tum_to_bag shifts sequences that start at 0 s
by 1 s, since ROS time 0 means "no time"). --errors writes each associated pose's absolute error
after the alignment ("timestamp,error_m"), to see which frames it comes from.

--map-frame-from FILE: the estimate is a localisation in a map's frame (a second session in a saved
map, the frames after a kidnap): FILE is a trajectory in that frame (the session that built the
map), whose alignment onto the ground truth brings the truth into the map's frame; each estimated
pose is then compared with it unaligned, and the share within 5 cm and 5 degrees is given.

--mesh: the vertex colours of a mesh (sdf_tracker_offline's mesh.ply) against the colour images
of the sequence it was made from (rgb.txt), seen from the estimated poses: every N-th frame
(default 10), each vertex that projects where the frame's depth is within 2 cm of it compared with
that pixel; the mean difference per channel and the mean and median RGB distance, in levels of 255.
)";

int run(int argc, char** argv) {
  using namespace sdf_tracker;
  const tools::CommandLine args(argc, argv,
                                {"groundtruth", "estimate", "plot", "errors", "estimate-time-offset", "map-frame-from",
                                 "mesh", "sequence", "frame-step"},
                                {"help"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
  if (args.has("mesh")) {
    const TriangleMesh mesh = io::readPlyMesh(args.get("mesh"));
    const TumSequence sequence = TumSequence::open(args.require("sequence"));
    const evaluation::ColourAgreement agreement = evaluation::compareMeshColours(
        mesh, sequence, io::readTrajectory(args.require("estimate")), args.getInt("frame-step", 10));
    std::cout << std::fixed << std::setprecision(2) << "mesh colours against " << agreement.frames
              << " colour images (" << agreement.comparisons << " vertex views): mean difference per channel "
              << agreement.mean_channel_difference << " levels of 255; RGB distance mean " << agreement.mean_distance
              << ", median " << agreement.median_distance << "\n";
    return agreement.comparisons > 0 ? 0 : 1;
  }
  const auto ground_truth = io::readTrajectory(args.require("groundtruth"));
  auto estimate = io::readTrajectory(args.require("estimate"));
  const double offset_s = args.getDouble("estimate-time-offset", 0.0);
  for (auto& pose : estimate) pose.timestamp_s -= offset_s;
  if (args.has("map-frame-from")) {
    const auto located =
        evaluation::computeLocalisation(estimate, ground_truth, io::readTrajectory(args.get("map-frame-from")));
    const size_t n = located.timestamps_s.size();
    const size_t within = located.within(0.05, 5.0 * M_PI / 180.0);
    std::cout << std::fixed << std::setprecision(1) << "in the map's frame: " << within << " of " << n
              << " poses within 5 cm and 5 degrees (" << (n ? 100.0 * within / n : 0.0) << " %); median error "
              << std::setprecision(4) << evaluation::summarize(located.translation_errors_m).median << " m, "
              << std::setprecision(2) << evaluation::summarize(located.rotation_errors_rad).median * 180.0 / M_PI
              << " degrees\n";
    if (args.has("errors")) {
      std::ostringstream csv;
      csv << "timestamp,error_m,error_deg\n" << std::fixed;
      for (size_t i = 0; i < n; ++i) {
        csv << std::setprecision(6) << located.timestamps_s[i] << ',' << std::setprecision(5)
            << located.translation_errors_m[i] << ',' << std::setprecision(3)
            << located.rotation_errors_rad[i] * 180.0 / M_PI << '\n';
      }
      io::writeTextFile(args.get("errors"), csv.str());
    }
    return 0;
  }
  const auto accuracy = tools::evaluateAccuracy(estimate, ground_truth);
  std::cout << tools::formatAccuracy(accuracy);
  if (args.has("plot")) tools::writeAccuracyPlot(args.get("plot"), accuracy, args.get("estimate"));
  if (args.has("errors")) {
    std::ostringstream csv;
    csv << "timestamp,error_m\n" << std::fixed;
    for (size_t i = 0; i < accuracy.ate.errors_m.size(); ++i) {
      csv << std::setprecision(6) << accuracy.ate.timestamps_s[i] << ',' << std::setprecision(5)
          << accuracy.ate.errors_m[i] << '\n';
    }
    io::writeTextFile(args.get("errors"), csv.str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return sdf_tracker::tools::runTool("sdf_tracker_evaluate", run, argc, argv); }
