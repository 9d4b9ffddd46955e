#include <gtest/gtest.h>

#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

/// The message of the std::invalid_argument that `fn` throws ("" when it throws none).
template <typename Fn>
std::string errorOf(Fn&& fn) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Parameters, OutOfRangeValuesAreRefusedWithTheNameTheRangeAndTheValueNeverClamped) {
  Settings settings = preset("default");
  const std::string cell = errorOf([&] { setParameterFromText(&settings, "CellSize", "-0.1"); });
  EXPECT_EQ(cell, "CellSize must be in [0.001, 1] m (got -0.1)");
  EXPECT_DOUBLE_EQ(settings.pipeline.volume.voxel_size_m, 0.02) << "a refused value changes nothing";
  EXPECT_EQ(errorOf([&] { setParameter(&settings, "MaxWeight", 0.0); }), "MaxWeight must be in (0, 1e+09] (got 0)");
  EXPECT_EQ(errorOf([&] { setParameter(&settings, "NegativeTruncationDistance", 0.05); }),
            "NegativeTruncationDistance must be in [-10, 0) m (got 0.05)");
  // Values that the reference's .cfg ranges used to clamp silently are taken as given.
  setParameter(&settings, "MaxDepth", 25.0);
  EXPECT_DOUBLE_EQ(settings.pipeline.max_depth_m, 25.0);
  setParameter(&settings, "MaxWeight", 20000.0);
  EXPECT_DOUBLE_EQ(settings.pipeline.integrator.max_weight, 20000.0);
  // Absurd values that a plain "> 0" let through.
  EXPECT_NE(errorOf([&] { setParameter(&settings, "CellSize", 1e-300); }), "");
  EXPECT_NE(errorOf([&] { setParameter(&settings, "FocalLengthX", 1e-30); }), "");
  EXPECT_NE(errorOf([&] { setParameterFromText(&settings, "TrackingSchedule", "1x0"); }), "");
}

TEST(Parameters, RulesBetweenParametersAreReportedInTheUsersWords) {
  Settings settings = preset("default");
  setParameter(&settings, "NegativeTruncationDistance", -0.005);
  setParameter(&settings, "MinDepth", 5.0);
  setParameter(&settings, "MaxDepth", 4.0);
  setParameter(&settings, "ImageWidth", 300);
  std::string all;
  for (const auto& v : settings.validate()) all += v + "\n";
  EXPECT_NE(all.find("NegativeTruncationDistance -0.005 m"), std::string::npos) << all;
  EXPECT_NE(all.find("CellSize (0.02 m)"), std::string::npos) << all;
  EXPECT_NE(all.find("MaxDepth (4 m) must be greater than MinDepth (5 m)"), std::string::npos) << all;
  EXPECT_NE(all.find("ImageWidth/ImageHeight"), std::string::npos) << all;
  EXPECT_EQ(all.find("_m "), std::string::npos) << "no struct field names: " << all;
  Settings compact = preset("default");
  setParameter(&compact, "MapType", std::string("dense"));
  setParameter(&compact, "CompactVoxels", true);
  setParameter(&compact, "MaxWeight", 300.0);
  ASSERT_TRUE(compact.keepToOneMapWhereNeeded({"MapType", "CompactVoxels", "MaxWeight"}, false));
  ASSERT_EQ(compact.validate().size(), 1u);
  EXPECT_EQ(compact.validate()[0], "MaxWeight must be at most 255.99609375 with CompactVoxels=true (got 300)");
}

TEST(Parameters, TheDenseGridsSizeAndPlacementGivenForTheSparseMapAreAcceptedAndTheUserToldTheyHaveNoEffect) {
  Settings sparse = preset("default");
  setParameter(&sparse, "GridSizeX", 200);
  setParameter(&sparse, "GridSizeZ", 120);
  EXPECT_TRUE(sparse.validate().empty());
  const std::vector<std::string> notes = sparse.withoutEffect({"CellSize", "GridSizeX", "GridSizeZ"});
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0].rfind("GridSizeX=200, GridSizeZ=120 have no effect with MapType=sparse", 0), 0u) << notes[0];
  EXPECT_NE(notes[0].find("set MapType=dense"), std::string::npos) << notes[0];
  EXPECT_TRUE(sparse.withoutEffect({"CellSize", "MaxMemoryMB"}).empty()) << "only what the user gave is named";
  setParameter(&sparse, "InitialCameraY", 0.3);
  const std::vector<std::string> placed = sparse.withoutEffect({"InitialCameraY"});
  ASSERT_EQ(placed.size(), 1u);
  EXPECT_EQ(placed[0].rfind("InitialCameraY=0.3 has no effect with MapType=sparse", 0), 0u) << placed[0];

  Settings dense = sparse;
  setParameter(&dense, "MapType", std::string("dense"));
  EXPECT_TRUE(dense.withoutEffect({"GridSizeX", "GridSizeZ", "InitialCameraY"}).empty())
      << "the dense grid reads them";
}

TEST(Parameters, ASwapDirectoryWithoutAMemoryBoundIsAcceptedAndTheUserToldItHasNoEffect) {
  Settings settings = preset("default");
  setParameter(&settings, "SwapDirectory", std::string("/data/swap"));
  EXPECT_TRUE(settings.validate().empty());
  const std::vector<std::string> notes = settings.withoutEffect({"SwapDirectory"});
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0], "SwapDirectory=/data/swap has no effect without MaxMemoryMB, the bound beyond which blocks go "
                      "to a swap file there; set MaxMemoryMB too");
  setParameter(&settings, "MaxMemoryMB", 512.0);
  EXPECT_TRUE(settings.withoutEffect({"SwapDirectory", "MaxMemoryMB"}).empty());
}

TEST(Parameters, TypesAreCheckedAndIntegersConvertOnlyWhenExact) {
  Settings settings;
  EXPECT_EQ(errorOf([&] { setParameterFromText(&settings, "CellSize", "abc"); }),
            "CellSize: expected a number, got \"abc\"");
  EXPECT_NE(errorOf([&] { setParameterFromText(&settings, "GridSizeX", "12.5"); }), "");
  EXPECT_NE(errorOf([&] { setParameterFromText(&settings, "GridSizeX", "1e10"); }), "") << "beyond int";
  EXPECT_NE(errorOf([&] { setParameterFromText(&settings, "GridSizeX", "-2147483648"); }), "");
  EXPECT_NE(errorOf([&] { setParameter(&settings, "CellSize", std::string("0.02")); }), "") << "typed: text is no number";
  EXPECT_NE(errorOf([&] { setParameter(&settings, "CompactVoxels", 1); }), "");
  setParameter(&settings, "GridSizeX", 128.0);  // a whole double is an int
  EXPECT_EQ(settings.pipeline.volume.dims.x(), 128);
  setParameter(&settings, "CellSize", 1);  // an int is a double
  EXPECT_DOUBLE_EQ(settings.pipeline.volume.voxel_size_m, 1.0);
  EXPECT_NE(errorOf([&] { setParameterFromText(&settings, "NoSuchParameter", "1"); }), "");
  EXPECT_NE(errorOf([&] { setParameterFromText(&settings, "TrackingSchedule", "4,2,1"); }), "");
  EXPECT_NE(errorOf([&] { setParameterFromText(&settings, "DepthWeighting", "loud"); }), "");
}

TEST(Parameters, EveryRowRoundTripsThroughTextAtFullPrecision) {
  Settings settings = preset("default");
  setParameter(&settings, "CellSize", 0.0123456789012345);
  for (const ParameterSpec& spec : parameterTable()) {
    const ParameterValue value = spec.get(settings);
    Settings copy = preset("paper");
    setParameterFromText(&copy, spec.name, toText(value));
    EXPECT_EQ(spec.get(copy), value) << spec.name << " = " << toText(value);
  }
  EXPECT_EQ(toText(0.02), "0.02");
}

TEST(Parameters, EveryRowsPresetDefaultsAreInItsRangeAndEveryPresetIsValid) {
  for (const ParameterSpec& spec : parameterTable()) {
    for (Preset p : {Preset::kDefault, Preset::kPaper, Preset::kReference}) {
      EXPECT_NO_THROW(spec.checkValue(spec.defaults.of(p))) << spec.name;
    }
    if (spec.range) {
      // Both ends of every range are accepted by the components too (or refused by a named rule).
      for (double end : {spec.range->low, spec.range->high}) {
        if (!spec.range->contains(end)) continue;
        Settings settings = preset("default");
        setParameter(&settings, spec.name, spec.type == ParameterType::kInt ? ParameterValue(static_cast<int>(end))
                                                                            : ParameterValue(end));
        for (const auto& v : settings.validate()) {
          EXPECT_EQ(v.find("_m "), std::string::npos) << spec.name << " = " << end << ": " << v;
        }
      }
    }
  }
  for (const auto& name : presetNames()) EXPECT_TRUE(preset(name).validate().empty()) << name;
  EXPECT_THROW(preset("fastest"), std::invalid_argument);
}

TEST(Parameters, EveryReferenceNameIsKnown) {
  for (const char* name : {"CellSize", "GridSizeX", "GridSizeY", "GridSizeZ", "PositiveTruncationDistance",
                           "NegativeTruncationDistance", "RobustStatisticCoefficient", "Regularization",
                           "MinPoseChangeToFuseData", "ConvergenceCondition", "MaximumRaycastSteps", "MaxWeight",
                           "ImageWidth", "ImageHeight", "FocalLengthX", "FocalLengthY", "CenterPointX",
                           "CenterPointY"}) {
    EXPECT_NE(findParameter(name), nullptr) << name;
  }
  EXPECT_EQ(findParameter("FocalLengthX")->readers, Readers::kNodeOnly) << "the offline runner must refuse it";
}

TEST(Parameters, PresetsMatchThePaperAndTheReferenceLaunchFile) {
  const Settings reference = preset("reference");
  EXPECT_EQ(reference.pipeline.volume.dims, Eigen::Vector3i(200, 200, 200));
  EXPECT_DOUBLE_EQ(reference.pipeline.volume.voxel_size_m, 0.02);
  EXPECT_DOUBLE_EQ(reference.pipeline.volume.positive_truncation_m, 0.08);
  EXPECT_DOUBLE_EQ(reference.pipeline.integrator.negative_truncation_m, -0.04);
  EXPECT_DOUBLE_EQ(reference.pipeline.min_pose_change_to_fuse, 0.01);
  EXPECT_EQ(formatSchedule(reference.pipeline.tracker.levels), "4x12,2x8,1x2");
  EXPECT_FALSE(reference.pipeline.predict_motion);
  const Settings paper = preset("paper");
  EXPECT_DOUBLE_EQ(paper.pipeline.volume.voxel_size_m, 0.03);
  EXPECT_DOUBLE_EQ(paper.pipeline.integrator.negative_truncation_m, -0.06);
  EXPECT_EQ(formatSchedule(paper.pipeline.tracker.levels), "4x12,2x6,1x2");
  EXPECT_EQ(paper.pipeline.integrator.weighting, MeasurementWeighting::kConstant);
}

}  // namespace
}  // namespace sdf_tracker
