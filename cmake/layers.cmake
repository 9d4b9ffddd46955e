# The package's folders as CMake targets, and the rule that keeps its layers apart.
#
# Every folder src/<part>/ (with its headers in include/sdf_tracker/<part>/) is one library,
# sdf_tracker_<part>, or a set of programs. Each names the parts it builds on (DEPENDS); a part may
# include its own headers and those of the parts it reaches through DEPENDS, and no others, always
# by their "sdf_tracker/<part>/..." path. Configuring fails, naming the file and the line, when a
# file breaks that rule, so the arrows of doc/ARCHITECTURE.md are the build's, not a convention.
# Cycles cannot be written: a part can only depend on parts declared before it.
#
# Expects SDF_TRACKER_ROOT (the repository) to be set.

# sdf_tracker_check_includes(<part> <reachable parts> <allow generated>)
function(sdf_tracker_check_includes part reachable allow_generated)
  file(GLOB files ${SDF_TRACKER_ROOT}/src/${part}/*.cpp ${SDF_TRACKER_ROOT}/src/${part}/*.h
    ${SDF_TRACKER_ROOT}/include/sdf_tracker/${part}/*.h)
  foreach(file ${files})
    file(RELATIVE_PATH name ${SDF_TRACKER_ROOT} ${file})
    file(STRINGS ${file} includes REGEX "^#include \"")
    foreach(line ${includes})
      string(REGEX REPLACE "^#include \"([^\"]+)\".*" "\\1" header "${line}")
      if(NOT header MATCHES "^sdf_tracker/")
        message(FATAL_ERROR "${name}: '${line}': include the package's headers by their "
          "sdf_tracker/<part>/... path, not relative to the file")
      endif()
      if(header MATCHES "^sdf_tracker/([^/]+)/")
        set(target_part ${CMAKE_MATCH_1})
        list(FIND reachable ${target_part} found)
        if(found EQUAL -1)
          message(FATAL_ERROR "${name}: '${line}': part '${part}' does not depend on '${target_part}' "
            "(it reaches: ${reachable}). See doc/ARCHITECTURE.md.")
        endif()
      elseif(NOT allow_generated)
        message(FATAL_ERROR "${name}: '${line}': a generated ROS header, outside the ROS layer")
      endif()
    endforeach()
  endforeach()
endfunction()

# The parts <part> reaches: itself and, transitively, its DEPENDS.
function(sdf_tracker_reach part depends out)
  set(reach ${part})
  foreach(dependency ${depends})
    get_property(dependency_reach GLOBAL PROPERTY SDF_TRACKER_REACH_${dependency})
    if(NOT dependency_reach)
      message(FATAL_ERROR "part '${part}' depends on '${dependency}', which is not declared before it")
    endif()
    list(APPEND reach ${dependency_reach})
  endforeach()
  list(REMOVE_DUPLICATES reach)
  set_property(GLOBAL PROPERTY SDF_TRACKER_REACH_${part} ${reach})
  set(${out} ${reach} PARENT_SCOPE)
endfunction()

# sdf_tracker_part(<part> [SOURCES <name>...] [PROGRAMS <name>...] [DEPENDS <part>...]
#                  [LINK <library or target>...] [GENERATED_HEADERS])
# SOURCES (src/<part>/<name>.cpp) make the library sdf_tracker_<part>; each of PROGRAMS
# (src/<part>/<name>.cpp) an executable <name> linked to the library, or to the DEPENDS when the
# part has no library. GENERATED_HEADERS lets the part include the package's generated ROS
# headers (messages, services, dynamic_reconfigure).
function(sdf_tracker_part part)
  cmake_parse_arguments(ARG "GENERATED_HEADERS" "" "SOURCES;PROGRAMS;DEPENDS;LINK" ${ARGN})
  sdf_tracker_reach(${part} "${ARG_DEPENDS}" reach)
  sdf_tracker_check_includes(${part} "${reach}" ${ARG_GENERATED_HEADERS})
  set(dependencies)
  foreach(dependency ${ARG_DEPENDS})
    if(TARGET sdf_tracker_${dependency})
      list(APPEND dependencies sdf_tracker_${dependency})
    endif()
  endforeach()
  set(program_links ${dependencies} ${ARG_LINK})
  if(ARG_SOURCES)
    list(TRANSFORM ARG_SOURCES PREPEND ${SDF_TRACKER_ROOT}/src/${part}/)
    list(TRANSFORM ARG_SOURCES APPEND .cpp)
    add_library(sdf_tracker_${part} ${ARG_SOURCES})
    target_include_directories(sdf_tracker_${part} PUBLIC ${SDF_TRACKER_ROOT}/include)
    target_link_libraries(sdf_tracker_${part} PUBLIC ${dependencies} ${ARG_LINK})
    # A shared library must resolve every symbol it uses from what it states it links.
    if(BUILD_SHARED_LIBS AND NOT SDF_TRACKER_SANITIZE)
      target_link_options(sdf_tracker_${part} PRIVATE -Wl,--no-undefined)
    endif()
    set(program_links sdf_tracker_${part})
  endif()
  foreach(program ${ARG_PROGRAMS})
    add_executable(${program} ${SDF_TRACKER_ROOT}/src/${part}/${program}.cpp)
    target_include_directories(${program} PRIVATE ${SDF_TRACKER_ROOT}/include)
    target_link_libraries(${program} ${program_links})
  endforeach()
endfunction()
