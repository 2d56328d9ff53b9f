# The test install_consumer (cmake -P): installs the build tree to a fresh prefix outside it,
# checks the layout, builds and runs tests/consumer against the installed package, and runs the
# installed `upd` from an unrelated directory so that it must find its configs from its own
# location. Arguments: -DBUILD_DIR -DSOURCE_DIR -DWORK_ROOT -DCXX [-DLAUNCHER] [-DGENERATOR].
cmake_minimum_required(VERSION 3.16)

string(RANDOM LENGTH 8 suffix)
set(work "${WORK_ROOT}/upd_nav_install_${suffix}")
set(prefix "${work}/prefix")
file(REMOVE_RECURSE "${work}")
file(MAKE_DIRECTORY "${work}/run")

# Runs ARGN from an unrelated directory; status 0 (or ${ok_status}) expected.
function(run_checked what)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY "${work}/run" RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 AND NOT rc STREQUAL "${ok_status}")
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(last_output "${out}${err}" PARENT_SCOPE)
endfunction()

function(expect_contains text needle what)
  string(FIND "${text}" "${needle}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${what}: expected '${needle}' in:\n${text}")
  endif()
endfunction()

# 1. Install and the layout.
run_checked("cmake --install" "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}")
foreach(f bin/upd lib/cmake/upd_nav/upd_navConfig.cmake
          lib/cmake/upd_nav/upd_navConfigVersion.cmake lib/cmake/upd_nav/upd_core-targets.cmake
          include/upd/core/pipeline.h include/upd/maps/traversability_grid.h
          share/upd-nav/README.md share/upd-nav/config/dune-kinect.ini
          share/upd-nav/config/dune-nav.ini share/upd-nav/config/ptg-dune.ini
          share/upd-nav/samples/rocks.ply)
  if(NOT EXISTS "${prefix}/${f}")
    message(FATAL_ERROR "not installed: ${prefix}/${f}")
  endif()
endforeach()
# A shared build's modules, beside the libraries (a static build has none).
foreach(f lib/libupd_mrpt_sensors.so lib/libupd_nav_viewer.so)
  if(EXISTS "${prefix}/lib/libupd_core.so" AND NOT EXISTS "${prefix}/${f}")
    message(FATAL_ERROR "not installed: ${prefix}/${f}")
  endif()
endforeach()
if(EXISTS "${prefix}/include/upd/maps/occupancy_grid.h")
  message(FATAL_ERROR "maps' public headers must not include MRPT (occupancy_grid.h is the bridge's)")
endif()
# The installed tool loads the installed libraries, not the build tree's.
run_checked("ldd upd" ldd "${prefix}/bin/upd")
string(REGEX MATCHALL "libupd_[a-z0-9_]+\\.so[^\n]*" libs "${last_output}")
foreach(l IN LISTS libs)
  string(FIND "${l}" "${prefix}/" at)
  if(at EQUAL -1 OR l MATCHES "not found")
    message(FATAL_ERROR "the installed upd loads ${l}")
  endif()
endforeach()

# 2. An outside project: find_package(upd_nav) + upd::core + upd::maps.
set(gen_args "")
if(GENERATOR)
  set(gen_args -G "${GENERATOR}")
endif()
set(launcher_args "")
if(LAUNCHER)
  set(launcher_args "-DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER}")
endif()
run_checked("configuring the consumer" "${CMAKE_COMMAND}" ${gen_args}
  -S "${SOURCE_DIR}/tests/consumer" -B "${work}/consumer" -DCMAKE_BUILD_TYPE=Release
  "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_CXX_COMPILER=${CXX}" ${launcher_args})
run_checked("building the consumer" "${CMAKE_COMMAND}" --build "${work}/consumer")
run_checked("running the consumer" "${work}/consumer/upd_consumer")
expect_contains("${last_output}" "zeta 1.0000" "the consumer")
message(STATUS "consumer: ${last_output}")

# 3. The installed tool finds its configs and data from its own location.
unset(ENV{UPD_NAV_DATA_DIR})
unset(ENV{UPD_CONFIG_DIR})
set(ENV{XDG_CACHE_HOME} "${work}/cache")
run_checked("upd params" "${prefix}/bin/upd" params --ini)
run_checked("upd analyze on the installed sample" "${prefix}/bin/upd" analyze
  "${prefix}/share/upd-nav/samples/rocks.ply" --stats-json "${work}/run/rocks.json")
# The sensors module is found beside the installed libraries (MRPT then names the driver).
file(WRITE "${work}/run/s.ini" "[CAM]\ndriver = CNoSuchSensor\n")
set(ok_status 1)
run_checked("upd live with a sensor file" "${prefix}/bin/upd" live --sensors "${work}/run/s.ini")
expect_contains("${last_output}" "unknown driver class 'CNoSuchSensor'" "the installed sensors module")
set(ok_status 3)  # 3: the goal is not reached in 2 s
run_checked("upd navigate with the default configs" "${prefix}/bin/upd" navigate
  --scenario rocks --max-time-s 2 --output "${work}/run/nav")
if(NOT EXISTS "${work}/run/nav/summary.json")
  message(FATAL_ERROR "upd navigate wrote no summary.json")
endif()

# 4. Nothing found: one line naming the places searched.
file(MAKE_DIRECTORY "${work}/bare/bin")
file(COPY "${prefix}/bin/upd" DESTINATION "${work}/bare/bin")
file(CREATE_LINK "${prefix}/lib" "${work}/bare/lib" SYMBOLIC)
execute_process(COMMAND "${work}/bare/bin/upd" navigate --scenario rocks --output "${work}/x"
                WORKING_DIRECTORY "${work}/run" RESULT_VARIABLE rc ERROR_VARIABLE err)
expect_contains("${err}" "${work}/bare/share/upd-nav/config" "upd without its data")
expect_contains("${err}" "UPD_NAV_DATA_DIR" "upd without its data")
string(REGEX MATCHALL "\n" newlines "${err}")
list(LENGTH newlines n)
if(NOT rc EQUAL 1 OR NOT n EQUAL 1)
  message(FATAL_ERROR "upd without its data: expected one line and status 1, got ${rc}:\n${err}")
endif()
set(ENV{UPD_NAV_DATA_DIR} "${prefix}/share/upd-nav")
run_checked("upd with UPD_NAV_DATA_DIR" "${work}/bare/bin/upd" navigate --scenario rocks
  --max-time-s 1 --output "${work}/run/nav2")

file(REMOVE_RECURSE "${work}")
