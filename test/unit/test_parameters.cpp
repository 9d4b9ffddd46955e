#include <gtest/gtest.h>

#include "sdf_tracker/core/parameters.h"
#include "sdf_tracker/core/pipeline.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

TEST(Parameters, InvalidValuesAreRejectedWithEveryViolationNamed) {
  Settings settings = preset("default");
  setParameter(&settings, "CellSize", "-0.1");
  setParameter(&settings, "MaxWeight", "0");
  setParameter(&settings, "NegativeTruncationDistance", "0.05");
  setParameter(&settings, "ImageWidth", "300");
  const auto violations = settings.validate();
  std::string all;
  for (const auto& v : violations) all += v + "\n";
  EXPECT_NE(all.find("voxel_size_m must be > 0 (got -0.1)"), std::string::npos) << all;
  EXPECT_NE(all.find("max_weight must be > 0 (got 0)"), std::string::npos) << all;
  EXPECT_NE(all.find("negative_truncation_m must be < 0 (got 0.05)"), std::string::npos) << all;
  EXPECT_NE(all.find("ImageWidth/ImageHeight"), std::string::npos) << all;
  EXPECT_THROW(SdfPipeline{settings.pipeline}, std::invalid_argument);
}

TEST(Parameters, TextThatDoesNotParseNamesTheParameterAndValue) {
  Settings settings;
  try {
    setParameter(&settings, "CellSize", "abc");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("CellSize"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("abc"), std::string::npos);
  }
  EXPECT_THROW(setParameter(&settings, "GridSizeX", "12.5"), std::invalid_argument);
  EXPECT_THROW(setParameter(&settings, "NoSuchParameter", "1"), std::invalid_argument);
  EXPECT_THROW(setParameter(&settings, "TrackingSchedule", "4,2,1"), std::invalid_argument);
}

TEST(Parameters, EveryReferenceNameIsKnownAndRoundTrips) {
  Settings settings;
  for (const char* name : {"CellSize", "GridSizeX", "GridSizeY", "GridSizeZ", "PositiveTruncationDistance",
                           "NegativeTruncationDistance", "RobustStatisticCoefficient", "Regularization",
                           "MinPoseChangeToFuseData", "ConvergenceCondition", "MaximumRaycastSteps", "MaxWeight",
                           "ImageWidth", "ImageHeight", "FocalLengthX", "FocalLengthY", "CenterPointX",
                           "CenterPointY"}) {
    const ParameterSpec* spec = findParameter(name);
    ASSERT_NE(spec, nullptr) << name;
    const std::string value = spec->get(settings);
    setParameter(&settings, name, value);
    EXPECT_EQ(spec->get(settings), value) << name;
  }
  setParameter(&settings, "TrackingSchedule", "8x3,1x1");
  EXPECT_EQ(formatSchedule(settings.pipeline.tracker.levels), "8x3,1x1");
}

TEST(Parameters, PresetsMatchThePaperAndTheReferenceLaunchFile) {
  const Settings reference = preset("reference");
  EXPECT_EQ(reference.pipeline.volume.dims, Eigen::Vector3i(200, 200, 200));
  EXPECT_DOUBLE_EQ(reference.pipeline.volume.voxel_size_m, 0.02);
  EXPECT_DOUBLE_EQ(reference.pipeline.volume.positive_truncation_m, 0.08);
  EXPECT_DOUBLE_EQ(reference.pipeline.integrator.negative_truncation_m, -0.04);
  EXPECT_EQ(formatSchedule(reference.pipeline.tracker.levels), "4x12,2x8,1x2");
  const Settings paper = preset("paper");
  EXPECT_DOUBLE_EQ(paper.pipeline.volume.voxel_size_m, 0.03);
  EXPECT_DOUBLE_EQ(paper.pipeline.integrator.negative_truncation_m, -0.06);
  EXPECT_EQ(formatSchedule(paper.pipeline.tracker.levels), "4x12,2x6,1x2");
  for (const auto& name : presetNames()) EXPECT_TRUE(preset(name).validate().empty()) << name;
  EXPECT_THROW(preset("fastest"), std::invalid_argument);
}

TEST(Pipeline, BadFramesLeaveMapAndPoseUntouched) {
  Settings settings = preset("default");
  settings.pipeline.volume.dims = Eigen::Vector3i(64, 64, 64);
  settings.pipeline.volume.voxel_size_m = 0.04;
  SdfPipeline pipeline(settings.pipeline);
  const PinholeCamera camera = test::testCamera();
  const FrameReport wrong_size = pipeline.processFrame(DepthImage(640, 480, 1.0f), camera);
  EXPECT_EQ(wrong_size.track.status, TrackStatus::kBadInput);
  const FrameReport empty = pipeline.processFrame(DepthImage(camera.width, camera.height, 0.0f), camera);
  EXPECT_EQ(empty.track.status, TrackStatus::kBadInput);
  EXPECT_FALSE(empty.fused);
  const FrameReport too_near = pipeline.processFrame(DepthImage(camera.width, camera.height, 0.2f), camera);
  EXPECT_EQ(too_near.track.status, TrackStatus::kBadInput) << "depth under MinDepth is no measurement";
  for (size_t i = 0; i < pipeline.volume().voxelCount(); ++i) ASSERT_EQ(pipeline.volume().voxel(i).weight, 0.0f);
  EXPECT_TRUE(pipeline.pose().isApprox(Eigen::Isometry3d::Identity()));
}

TEST(Pipeline, LiveUpdatesValidateAndRefuseGridChanges) {
  Settings settings = preset("default");
  settings.pipeline.volume.dims = Eigen::Vector3i(32, 32, 32);
  SdfPipeline pipeline(settings.pipeline);
  PipelineConfig candidate = pipeline.config();
  candidate.integrator.max_weight = 10.0;
  pipeline.updateConfig(candidate);
  EXPECT_DOUBLE_EQ(pipeline.config().integrator.max_weight, 10.0);
  candidate.integrator.max_weight = -1.0;
  EXPECT_THROW(pipeline.updateConfig(candidate), std::invalid_argument);
  EXPECT_DOUBLE_EQ(pipeline.config().integrator.max_weight, 10.0) << "a rejected update changes nothing";
  candidate = pipeline.config();
  candidate.volume.voxel_size_m = 0.05;
  EXPECT_THROW(pipeline.updateConfig(candidate), std::invalid_argument);
  candidate = pipeline.config();
  candidate.volume.compact_voxels = true;
  EXPECT_THROW(pipeline.updateConfig(candidate), std::invalid_argument) << "the storage belongs to the grid";
}

}  // namespace
}  // namespace sdf_tracker
