# The ROS-free core: library `binloop_core` and its gtests. Included by the catkin package and by the
# plain CMake project in cmake/core_only, which builds and tests the core with no ROS at all.
# Expects BINLOOP_ROOT to point at the repository root.

set(CMAKE_CXX_STANDARD 17)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
set(CMAKE_CXX_EXTENSIONS OFF)
if(NOT CMAKE_BUILD_TYPE)
  set(CMAKE_BUILD_TYPE RelWithDebInfo)
endif()
set(BINLOOP_WARNINGS -Wall -Wextra -Wno-unused-parameter)
# The project's own builds (scripts/build.sh, hence the tests and CI) turn warnings into errors; a package
# built by someone else's catkin_make does not, as another compiler may warn about more.
option(BINLOOP_WERROR "treat warnings as errors" OFF)
if(BINLOOP_WERROR)
  list(APPEND BINLOOP_WARNINGS -Werror)
endif()

find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs features2d calib3d)
find_package(Eigen3 REQUIRED NO_MODULE)
find_package(Threads REQUIRED)
# Ceres (optim: pose optimisation, local bundle adjustment). Debian's CMake package (2.1) points
# Ceres::ceres at the static libceres.a although the shared libceres.so is installed beside it; linking the
# archive would copy Ceres into libbinloop_core.so and export it from there. Take the shared library when
# there is one (a no-op where the package already names it).
find_package(Ceres REQUIRED)
foreach(cfg IMPORTED_LOCATION IMPORTED_LOCATION_RELEASE IMPORTED_LOCATION_NOCONFIG)
  get_target_property(ceres_lib Ceres::ceres ${cfg})
  if(ceres_lib MATCHES "\\.a$")
    string(REGEX REPLACE "\\.a$" ".so" ceres_so "${ceres_lib}")
    if(EXISTS "${ceres_so}")
      set_target_properties(Ceres::ceres PROPERTIES ${cfg} "${ceres_so}")
    endif()
  endif()
endforeach()

# CHOLMOD (SuiteSparse, which Ceres needs too): the sparse Cholesky of global bundle adjustment.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)

file(GLOB_RECURSE BINLOOP_CORE_SOURCES CONFIGURE_DEPENDS ${BINLOOP_ROOT}/src/core/*.cpp)
add_library(binloop_core SHARED ${BINLOOP_CORE_SOURCES})
target_include_directories(binloop_core PUBLIC ${BINLOOP_ROOT}/include ${OpenCV_INCLUDE_DIRS})
target_include_directories(binloop_core PRIVATE ${CHOLMOD_INCLUDE_DIR})
target_link_libraries(binloop_core PUBLIC Eigen3::Eigen ${OpenCV_LIBS} Threads::Threads Ceres::ceres
                      PRIVATE ${CHOLMOD_LIBRARY} ${CMAKE_DL_LIBS})
target_compile_options(binloop_core PRIVATE ${BINLOOP_WARNINGS})
# The last place packageDir() looks for vocab/ and config/ (util/package_paths.h).
set_source_files_properties(${BINLOOP_ROOT}/src/core/util/package_paths.cpp PROPERTIES
                            COMPILE_DEFINITIONS BINLOOP_SOURCE_DIR="${BINLOOP_ROOT}")
# Hamming distances are four popcounts; without the POPCNT instruction GCC calls a bit-twiddling
# helper instead, which made the vocabulary-tree descent ~3x slower. Every x86-64 CPU since 2008 has
# it; other architectures (arm64) have their own and ignore this.
include(CheckCXXCompilerFlag)
check_cxx_compiler_flag(-mpopcnt BINLOOP_HAS_MPOPCNT)
if(BINLOOP_HAS_MPOPCNT)
  target_compile_options(binloop_core PUBLIC -mpopcnt)
endif()

# Where tests find ../shared/data; the environment variable BINLOOP_SHARED_DATA overrides it at run time.
get_filename_component(BINLOOP_SHARED_DATA_DIR ${BINLOOP_ROOT}/../shared/data ABSOLUTE)

# Small helpers the tests share (temporary folders, where shared data is, tiny data makers).
file(GLOB BINLOOP_TEST_SUPPORT_SOURCES CONFIGURE_DEPENDS ${BINLOOP_ROOT}/test/support/*.cpp)

# One gtest executable per test/core/**/<name>_test.cpp; the file name decides the role.
function(binloop_add_core_tests)
  find_package(GTest REQUIRED)
  include(GoogleTest)
  add_library(binloop_test_support STATIC ${BINLOOP_TEST_SUPPORT_SOURCES})
  target_include_directories(binloop_test_support PUBLIC ${BINLOOP_ROOT}/test)
  target_compile_definitions(binloop_test_support PUBLIC BINLOOP_SHARED_DATA_DIR="${BINLOOP_SHARED_DATA_DIR}"
                             BINLOOP_ROOT_DIR="${BINLOOP_ROOT}")
  target_link_libraries(binloop_test_support PUBLIC binloop_core GTest::gtest)
  file(GLOB_RECURSE tests CONFIGURE_DEPENDS ${BINLOOP_ROOT}/test/core/*_test.cpp)
  foreach(t ${tests})
    get_filename_component(name ${t} NAME_WE)
    add_executable(${name} ${t})
    target_link_libraries(${name} binloop_test_support GTest::gtest_main)
    target_compile_options(${name} PRIVATE ${BINLOOP_WARNINGS})
    gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 600)
  endforeach()
endfunction()
