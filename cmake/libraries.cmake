# The ROS-free parts of the package (the tracker, its file formats, the simulator, the evaluation,
# the cameras' recording formats and the command-line tools) and the unit tests' sources. Included
# by the catkin package (CMakeLists.txt) and by the sanitizer/fuzzing build (test/sanitize/), so
# each list exists once. Expects Eigen3, OpenCV, Ceres and (optionally) OpenMP to be found by the
# includer.
# The parts and their arrows are drawn in doc/ARCHITECTURE.md; cmake/layers.cmake enforces them.

get_filename_component(SDF_TRACKER_ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
include(${CMAKE_CURRENT_LIST_DIR}/layers.cmake)

# Eigen and OpenMP reach every part through util.
set(SDF_TRACKER_PARALLEL)
if(OpenMP_CXX_FOUND)
  set(SDF_TRACKER_PARALLEL OpenMP::OpenMP_CXX)
endif()
add_library(sdf_tracker_eigen INTERFACE)
target_include_directories(sdf_tracker_eigen SYSTEM INTERFACE ${EIGEN3_INCLUDE_DIR})

# The tracker: Eigen and OpenMP only.
sdf_tracker_part(util SOURCES frame_memory memory se3 LINK sdf_tracker_eigen ${SDF_TRACKER_PARALLEL})
sdf_tracker_part(camera SOURCES camera colour_image depth_image depth_undistortion sensor_model DEPENDS util)
sdf_tracker_part(map SOURCES block_swap map_merge overlaid_map sparse_tsdf_map tsdf_map tsdf_volume DEPENDS util)
sdf_tracker_part(fusion SOURCES integrator DEPENDS camera map)
sdf_tracker_part(tracking SOURCES motion_model tracker DEPENDS camera map)
sdf_tracker_part(surface SOURCES chunked_mesh raycaster surface DEPENDS camera map)
# Finding the camera again: the places the map was built from, and the search among them.
sdf_tracker_part(places SOURCES place_descriptor place_memory DEPENDS camera)
sdf_tracker_part(relocalisation SOURCES coarse_field relocaliser view_agreement DEPENDS tracking surface places)
# Loop closure: the pose graph over submaps, solved by Ceres.
sdf_tracker_part(graph SOURCES background_solver pose_graph DEPENDS util LINK Ceres::ceres)
sdf_tracker_part(pipeline SOURCES loop_closure parameters pipeline submap_store submaps tracked_path
  DEPENDS fusion tracking surface relocalisation graph)

# Around the tracker: files (OpenCV for images only), the synthetic scenes, trajectory errors.
sdf_tracker_part(io SOURCES colour_image_file depth_png files map_file mesh_file sdfmap_file trajectory_file tum_sequence vti_file
  DEPENDS camera map surface places pipeline LINK ${OpenCV_LIBS})
target_include_directories(sdf_tracker_io SYSTEM PRIVATE ${OpenCV_INCLUDE_DIRS})
sdf_tracker_part(sim SOURCES relocalisation_cases synthetic wheel_odometry DEPENDS io)
sdf_tracker_part(eval SOURCES colour_agreement evaluation DEPENDS io)

# Depth cameras' own formats, without ROS or the vendors' libraries: the Kinect v1's disparity
# model, fakenect recordings and OpenNI .oni files.
sdf_tracker_part(devices SOURCES fakenect_dump kinect_disparity oni_file recording DEPENDS io)

# What the command-line tools share (with the ROS layer's tools too): arguments, output folders,
# reports; and the tools.
sdf_tracker_part(cli SOURCES command_line odometry_track option_values output_folder report tracker_alone
  DEPENDS pipeline io eval)
sdf_tracker_part(tools PROGRAMS sdf_tracker_offline sdf_tracker_synth sdf_tracker_evaluate tum_to_fakenect tum_to_oni
  DEPENDS cli sim devices)

set(SDF_TRACKER_TEST_DIR ${SDF_TRACKER_ROOT}/test)
# The core's unit tests: milliseconds to seconds each, run in the release build and again under
# the sanitizers.
set(SDF_TRACKER_UNIT_TEST_SOURCES
  ${SDF_TRACKER_TEST_DIR}/support/test_main.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_camera_volume.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_integrator.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_tracker.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_io.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_colour.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_loop_closure.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_tum_sequence.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_evaluation.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_parameters.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_pipeline.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_pose_graph.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_raycaster.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_relocalisation.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_sparse_map.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_submaps.cpp
  ${SDF_TRACKER_TEST_DIR}/unit/test_synthetic_sensor.cpp
)
set(SDF_TRACKER_UNIT_TEST_LIBRARIES sdf_tracker_pipeline sdf_tracker_graph sdf_tracker_io sdf_tracker_sim sdf_tracker_eval)
# Whole sequences through the pipeline, synthetic and (when ../shared/data has them) real: seconds
# to a minute each, run in the release build only.
set(SDF_TRACKER_SEQUENCE_TEST_SOURCES ${SDF_TRACKER_TEST_DIR}/support/test_main.cpp
  ${SDF_TRACKER_TEST_DIR}/sequences/test_end_to_end.cpp ${SDF_TRACKER_TEST_DIR}/sequences/test_map_sequences.cpp
  ${SDF_TRACKER_TEST_DIR}/sequences/test_relocalisation_runs.cpp
  ${SDF_TRACKER_TEST_DIR}/sequences/test_odometry_prior.cpp ${SDF_TRACKER_TEST_DIR}/sequences/test_loop_closure_runs.cpp)
# The command-line tools' tests: their libraries, and the programs run as a user runs them.
set(SDF_TRACKER_TOOLS_TEST_SOURCES ${SDF_TRACKER_TEST_DIR}/support/test_main.cpp
  ${SDF_TRACKER_TEST_DIR}/tools/test_tools.cpp ${SDF_TRACKER_TEST_DIR}/tools/test_devices.cpp)
set(SDF_TRACKER_TOOLS_TEST_LIBRARIES sdf_tracker_cli sdf_tracker_devices sdf_tracker_sim)
