#include <gtest/gtest.h>

#include "scratch_directory.h"

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  const int result = RUN_ALL_TESTS();
  sdf_tracker::test::removeScratchDirectories(result == 0);
  return result;
}
