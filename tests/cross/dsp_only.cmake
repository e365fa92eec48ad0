# RSD_DSP_ONLY: dsp's geometry and rectification with their tests, nothing else (no LCM, OpenCV,
# Ceres...): what the arm64 cross build compiles and runs under qemu (tests/cross/run.sh).
#
# Eigen, Boost.Math and Highway's headers are the same for every architecture (Debian installs
# them once, in /usr/include); the cross compiler must not search /usr/include itself (the
# build machine's C library lives there), so it sees just those three through a directory of
# links. Highway's arm64 library is Debian's multiarch libhwy-dev:arm64; GoogleTest is built
# from the sources Debian's libgtest-dev installs in /usr/src/googletest.
set(RSD_CROSS_INCLUDE ${CMAKE_BINARY_DIR}/cross-include)
file(MAKE_DIRECTORY ${RSD_CROSS_INCLUDE})
foreach(pair "boost;/usr/include/boost" "Eigen;/usr/include/eigen3/Eigen" "hwy;/usr/include/hwy")
  list(GET pair 0 name)
  list(GET pair 1 target)
  if(NOT EXISTS ${target})
    message(FATAL_ERROR "RSD_DSP_ONLY: ${target} is missing (tools/setup.sh installs it)")
  endif()
  file(CREATE_LINK ${target} ${RSD_CROSS_INCLUDE}/${name} SYMBOLIC)
endforeach()

add_library(Eigen3::Eigen INTERFACE IMPORTED)
target_include_directories(Eigen3::Eigen INTERFACE ${RSD_CROSS_INCLUDE})

find_library(RSD_HWY_LIBRARY NAMES hwy PATHS /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE} NO_DEFAULT_PATH NO_CMAKE_FIND_ROOT_PATH)
if(NOT RSD_HWY_LIBRARY)
  message(FATAL_ERROR "RSD_DSP_ONLY: no Highway library for ${CMAKE_LIBRARY_ARCHITECTURE} "
                      "(libhwy-dev:arm64; tools/setup.sh installs it)")
endif()
add_library(hwy::hwy SHARED IMPORTED)
set_target_properties(hwy::hwy PROPERTIES IMPORTED_LOCATION ${RSD_HWY_LIBRARY}
                                          INTERFACE_INCLUDE_DIRECTORIES ${RSD_CROSS_INCLUDE})
# libhwy's own dependencies (libstdc++, libc) resolve in the multiarch directory at link time.
add_link_options(-Wl,-rpath-link,/usr/lib/${CMAKE_LIBRARY_ARCHITECTURE})

set(BUILD_GMOCK OFF CACHE BOOL "" FORCE)
set(INSTALL_GTEST OFF CACHE BOOL "" FORCE)
add_subdirectory(/usr/src/googletest ${CMAKE_BINARY_DIR}/googletest EXCLUDE_FROM_ALL)
# GoogleTest's own sources, not ours: GCC 12 warns falsely in them (-Wrestrict in gtest.cc).
target_compile_options(gtest PRIVATE -w)
target_compile_options(gtest_main PRIVATE -w)
if(NOT TARGET GTest::gtest)
  add_library(GTest::gtest ALIAS gtest)
  add_library(GTest::gtest_main ALIAS gtest_main)
endif()

# The libraries as unity translation units, as in the other trees (CMakeLists.txt,
# RSD_UNITY_BUILD, the same batches): the geometry's six files and the rectifier's five share
# their Eigen templates, parsed and instantiated once instead of once per file.
set(CMAKE_UNITY_BUILD ON)
set(CMAKE_UNITY_BUILD_BATCH_SIZE 8)

enable_testing()
add_subdirectory(dsp)
add_subdirectory(tests)
