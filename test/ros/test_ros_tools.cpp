// The ROS tools as a user runs them: tum_to_bag on a disk that fills up while it writes.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "sdf_tracker/sim/synthetic.h"
#include "run_command.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

namespace fs = std::filesystem;

TEST(TumToBag, ADiskThatFillsUpWhileWritingGivesAnErrorAndLeavesNoFile) {
  const std::string dir = test::scratchDirectory("full_disk");
  synthetic::SequenceSpec spec;
  spec.frames = 3;
  spec.camera = test::testCamera();
  synthetic::writeSequence(dir + "/sequence", spec);
  // The bag's temporary is a full disk: every write to it fails with ENOSPC.
  const std::string bag = dir + "/sequence.bag";
  ASSERT_EQ(::symlink("/dev/full", (bag + ".partial").c_str()), 0);
  const test::CommandResult run = test::runCommand(std::string(TUM_TO_BAG) + " " + dir + "/sequence " + bag);
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("tum_to_bag: error: " + bag + ": writing the bag failed ("), std::string::npos)
      << run.output;
  EXPECT_FALSE(fs::exists(fs::symlink_status(bag))) << "no bag under the final name";
  EXPECT_FALSE(fs::exists(fs::symlink_status(bag + ".partial"))) << "the temporary is removed";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sdf_tracker
