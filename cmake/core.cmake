# The ROS-free core library and the command-line tools' library, and the unit tests' sources.
# Included by the catkin package (CMakeLists.txt) and by the sanitizer/fuzzing build
# (test/sanitize/CMakeLists.txt), so the source lists exist once. Expects Eigen3, OpenCV and
# (optionally) OpenMP to be found by the includer.

get_filename_component(SDF_TRACKER_ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)

# The ROS-free core: Eigen, OpenMP, and OpenCV for image files only.
add_library(sdf_tracker_core
  ${SDF_TRACKER_ROOT}/src/core/block_swap.cpp
  ${SDF_TRACKER_ROOT}/src/core/camera.cpp
  ${SDF_TRACKER_ROOT}/src/core/chunked_mesh.cpp
  ${SDF_TRACKER_ROOT}/src/core/depth_undistortion.cpp
  ${SDF_TRACKER_ROOT}/src/core/depth_image.cpp
  ${SDF_TRACKER_ROOT}/src/core/evaluation.cpp
  ${SDF_TRACKER_ROOT}/src/core/frame_memory.cpp
  ${SDF_TRACKER_ROOT}/src/core/integrator.cpp
  ${SDF_TRACKER_ROOT}/src/core/io.cpp
  ${SDF_TRACKER_ROOT}/src/core/motion_model.cpp
  ${SDF_TRACKER_ROOT}/src/core/parameters.cpp
  ${SDF_TRACKER_ROOT}/src/core/pipeline.cpp
  ${SDF_TRACKER_ROOT}/src/core/raycaster.cpp
  ${SDF_TRACKER_ROOT}/src/core/se3.cpp
  ${SDF_TRACKER_ROOT}/src/core/sensor_model.cpp
  ${SDF_TRACKER_ROOT}/src/core/sparse_tsdf_map.cpp
  ${SDF_TRACKER_ROOT}/src/core/surface.cpp
  ${SDF_TRACKER_ROOT}/src/core/synthetic.cpp
  ${SDF_TRACKER_ROOT}/src/core/tracker.cpp
  ${SDF_TRACKER_ROOT}/src/core/tsdf_map.cpp
  ${SDF_TRACKER_ROOT}/src/core/tsdf_volume.cpp
  ${SDF_TRACKER_ROOT}/src/core/tum_sequence.cpp
)
target_include_directories(sdf_tracker_core PUBLIC ${SDF_TRACKER_ROOT}/include)
target_include_directories(sdf_tracker_core SYSTEM PUBLIC ${EIGEN3_INCLUDE_DIR} ${OpenCV_INCLUDE_DIRS})
target_link_libraries(sdf_tracker_core PUBLIC ${OpenCV_LIBS})
if(OpenMP_CXX_FOUND)
  target_link_libraries(sdf_tracker_core PUBLIC OpenMP::OpenMP_CXX)
endif()

# Command-line tools (TUM folder in; trajectory, mesh, report out).
set(SDF_TRACKER_TOOLS_DIR ${SDF_TRACKER_ROOT}/src/tools)
add_library(sdf_tracker_tools ${SDF_TRACKER_TOOLS_DIR}/report.cpp ${SDF_TRACKER_TOOLS_DIR}/command_line.cpp
  ${SDF_TRACKER_TOOLS_DIR}/output_folder.cpp)
target_link_libraries(sdf_tracker_tools PUBLIC sdf_tracker_core)

foreach(tool sdf_tracker_offline sdf_tracker_synth sdf_tracker_evaluate)
  add_executable(${tool} ${SDF_TRACKER_TOOLS_DIR}/${tool}.cpp)
  target_link_libraries(${tool} sdf_tracker_tools)
endforeach()

# Depth cameras' own formats, without ROS or the vendors' libraries: the Kinect v1's disparity
# model, fakenect recordings and OpenNI .oni files; and the converters from TUM folders to them.
add_library(sdf_tracker_devices
  ${SDF_TRACKER_ROOT}/src/devices/fakenect_dump.cpp
  ${SDF_TRACKER_ROOT}/src/devices/kinect_disparity.cpp
  ${SDF_TRACKER_ROOT}/src/devices/oni_file.cpp
  ${SDF_TRACKER_ROOT}/src/devices/recording.cpp
)
target_link_libraries(sdf_tracker_devices PUBLIC sdf_tracker_core)
foreach(tool tum_to_fakenect tum_to_oni)
  add_executable(${tool} ${SDF_TRACKER_TOOLS_DIR}/${tool}.cpp)
  target_link_libraries(${tool} sdf_tracker_tools sdf_tracker_devices)
endforeach()

set(SDF_TRACKER_UNIT_TEST_DIR ${SDF_TRACKER_ROOT}/test/unit)
set(SDF_TRACKER_CORE_TEST_SOURCES
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_main.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_camera_volume.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_integrator.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_tracker.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_io.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_evaluation.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_parameters.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_pipeline.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_raycaster.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_sparse_map.cpp
)
set(SDF_TRACKER_TOOLS_TEST_SOURCES ${SDF_TRACKER_UNIT_TEST_DIR}/test_main.cpp ${SDF_TRACKER_UNIT_TEST_DIR}/test_tools.cpp
  ${SDF_TRACKER_UNIT_TEST_DIR}/test_devices.cpp)
