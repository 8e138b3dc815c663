# Fails when the core depends on ROS. Debian installs ROS headers in /usr/include next to everything
# else, so the compiler cannot keep them out; this check does, three ways:
#  1. no `#include` in src/core or include/binloop names a ROS package's header;
#  2. no compiled core object depended on a header of a ROS package (the compiler's .d files, so a ROS
#     header reached through another header is caught as well);
#  3. the core library links no ROS library.
# ROS packages are those with /usr/share/<name>/package.xml (how Debian installs them), plus roscpp's
# `ros/` headers and catkin devel spaces (generated messages).
file(GLOB ros_manifests /usr/share/*/package.xml)
set(ros_pkgs ros)
foreach(m ${ros_manifests})
  get_filename_component(d ${m} DIRECTORY)
  get_filename_component(n ${d} NAME)
  list(APPEND ros_pkgs ${n})
endforeach()
list(REMOVE_DUPLICATES ros_pkgs)
list(JOIN ros_pkgs "|" alt)
set(problems "")

file(GLOB_RECURSE core_files ${ROOT}/src/core/*.cpp ${ROOT}/src/core/*.h ${ROOT}/include/binloop/*.h)
foreach(f ${core_files})
  file(STRINGS ${f} hits REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"](${alt})/")
  foreach(h ${hits})
    string(STRIP "${h}" h)
    list(APPEND problems "${f}: ${h}")
  endforeach()
endforeach()

file(GLOB_RECURSE depfiles ${BUILD}/CMakeFiles/binloop_core.dir/*.d)
if(NOT depfiles)
  list(APPEND problems "no compiler dependency files under ${BUILD}: cannot check transitive includes")
endif()
foreach(d ${depfiles})
  file(READ ${d} content)
  string(REGEX MATCHALL "/usr/include/(${alt})/[^ \t\r\n\\\\]+|[^ \t\r\n]*/devel/include/[^ \t\r\n\\\\]+" hits "${content}")
  if(hits)
    list(GET hits 0 first)
    list(APPEND problems "${d}: depends on ROS header ${first}")
  endif()
endforeach()

execute_process(COMMAND ldd ${LIB} OUTPUT_VARIABLE libs)
string(REGEX MATCHALL "lib(roscpp|rosbag|rosconsole|rostime|cpp_common|xmlrpcpp|nodeletlib|class_loader|roslib)[^ ]*" ros_libs "${libs}")
if(ros_libs)
  list(APPEND problems "${LIB} links ROS libraries: ${ros_libs}")
endif()

list(LENGTH depfiles n)
if(problems)
  list(JOIN problems "\n  " msg)
  message(FATAL_ERROR "The core must not use ROS, but:\n  ${msg}")
endif()
message(STATUS "core_has_no_ros: ${n} core objects and their headers are ROS-free")
