// sdf_tracker_evaluate: ATE and RPE of a TUM trajectory against ground truth, with a plot.

#include <iomanip>
#include <iostream>
#include <sstream>

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/cli/report.h"
#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/trajectory_file.h"

namespace {

const char* kUsage = R"(usage: sdf_tracker_evaluate --groundtruth FILE --estimate FILE [--plot FILE.png]
                            [--errors FILE.csv] [--estimate-time-offset S]

Absolute trajectory error (rigid alignment) and relative pose error (1 s window), as defined by
the TUM RGB-D benchmark; timestamps are associated within 0.02 s. --estimate-time-offset S is
subtracted from the estimate's timestamps first (tum_to_bag shifts sequences that start at 0 s
by 1 s, since ROS time 0 means "no time"). --errors writes each associated pose's absolute error
after the alignment ("timestamp,error_m"), to see which frames it comes from.
)";

int run(int argc, char** argv) {
  using namespace sdf_tracker;
  const tools::CommandLine args(argc, argv, {"groundtruth", "estimate", "plot", "errors", "estimate-time-offset"},
                                {"help"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
  const auto ground_truth = io::readTrajectory(args.require("groundtruth"));
  auto estimate = io::readTrajectory(args.require("estimate"));
  const double offset_s = args.getDouble("estimate-time-offset", 0.0);
  for (auto& pose : estimate) pose.timestamp_s -= offset_s;
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
