# The ROS 1 layer's tests (included when upd::ros1 was built): the message conversions, bags
# (written with the rosbag API, played back by `upd playback`), and the node against a real
# master on the loopback (node_test.cpp starts roscore itself).
find_package(OpenCV 4 REQUIRED COMPONENTS core imgcodecs)
upd_add_tests_in(ros LIBS upd::ros1 upd::sim upd::nav opencv_core opencv_imgcodecs)
foreach(t ros_bag_test ros_node_test)
  if(TARGET ${t})
    target_compile_definitions(${t} PRIVATE UPD_BINARY="$<TARGET_FILE:upd>")
    add_dependencies(${t} upd)
  endif()
endforeach()
if(TARGET ros_node_test)  # the launch file and the node's entry script, as the build tree holds them
  target_compile_definitions(ros_node_test PRIVATE UPD_DATA_BUILD_DIR="${UPD_DATA_BUILD_DIR}")
endif()
