# Sanitizer and fuzzing instrumentation for pcl_movers (issue #8, docs/reliability.md).
#
#   -DPCL_MOVERS_SANITIZE=ON        AddressSanitizer + UndefinedBehaviorSanitizer on everything this
#                                   project compiles (library, tools, tests). GCC or Clang.
#   -DPCL_MOVERS_BUILD_FUZZERS=ON   libFuzzer targets in test/fuzz (Clang only); the library is then
#                                   compiled with -fsanitize=fuzzer-no-link,address,undefined.
#
# PCL, VTK, Boost and FLANN come from Debian and are not instrumented. That is fine for ASan/UBSan:
# the runtime intercepts malloc/free for the whole process, so heap errors in our code that touch
# PCL-allocated memory are still caught; only bugs *inside* PCL go unseen. The options are applied
# with add_compile_options/add_link_options, so this file must be included before the first target.

option(PCL_MOVERS_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
option(PCL_MOVERS_BUILD_FUZZERS "Build the libFuzzer targets in test/fuzz (Clang only)" OFF)

if(PCL_MOVERS_SANITIZE OR PCL_MOVERS_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    message(FATAL_ERROR "PCL_MOVERS_SANITIZE / PCL_MOVERS_BUILD_FUZZERS need GCC or Clang")
  endif()
  # -fno-sanitize-recover: a UB report aborts the process, so ctest sees a failure instead of a
  # log line nobody reads. vptr is left out because it needs RTTI of every polymorphic type it
  # checks, and the uninstrumented PCL/VTK libraries make it report false positives across the
  # shared-library boundary.
  set(PCL_MOVERS_SANITIZER_FLAGS
      -fsanitize=address,undefined -fno-sanitize=vptr -fno-sanitize-recover=undefined
      -fno-omit-frame-pointer)
  add_compile_options(${PCL_MOVERS_SANITIZER_FLAGS})
  # Eigen (Memory.h) stops trusting glibc's 16-byte malloc alignment when __SANITIZE_ADDRESS__ is
  # defined and switches to its handmade aligned malloc/free, which store an offset before the
  # block. The uninstrumented PCL keeps plain malloc/free, so an Eigen vector resized inside PCL
  # and freed in our code (or the reverse) would be freed by the wrong scheme: ASan reported this
  # as a heap-buffer-overflow in handmade_aligned_free under GroundPlaneFilter::fitPlane. Keep one
  # allocation scheme for the whole process, as in the normal build.
  add_compile_definitions(EIGEN_MALLOC_ALREADY_ALIGNED=1)
  add_link_options(-fsanitize=address,undefined -fno-sanitize=vptr)
  message(STATUS "pcl_movers: AddressSanitizer + UndefinedBehaviorSanitizer enabled")
endif()

if(PCL_MOVERS_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "PCL_MOVERS_BUILD_FUZZERS needs Clang (-fsanitize=fuzzer); configure with "
                        "-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++")
  endif()
  # Coverage instrumentation for everything; only the fuzz targets link libFuzzer's main.
  add_compile_options(-fsanitize=fuzzer-no-link)
  message(STATUS "pcl_movers: libFuzzer targets enabled")
endif()
