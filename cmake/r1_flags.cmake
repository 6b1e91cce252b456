# Compiler flags shared by every target (requirement R1-NUM-001: no fast-math, no FMA contraction).
add_compile_options(
  -ffp-contract=off      # no fused multiply-add: a*b+c rounds twice everywhere
  -fno-fast-math
  -fno-finite-math-only
  -Wall -Wextra -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Wunused
  -Woverloaded-virtual -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough)
# Eigen's own fast math (on by default) computes a float vector's sqrt from an approximate
# reciprocal and one Newton step: off, so Eigen's array sqrt is IEEE's like std::sqrt.
add_compile_definitions(EIGEN_FAST_MATH=0)
if(R1_WERROR)
  add_compile_options(-Werror)
endif()
if(R1_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()
if(R1_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "R1_FUZZ needs clang (configure with -DCMAKE_CXX_COMPILER=clang++-14)")
  endif()
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  # libFuzzer's coverage (edge counters and comparison hooks) instruments the libraries the fuzz
  # targets drive, and the fuzz targets themselves (fuzz/CMakeLists.txt), not the other executables
  # (the tests, r1): their code is never fuzzed, and the hooks cost about an eighth of each of their
  # compiles and a call per comparison as they run (R1-TEST-040).
  add_compile_options($<$<NOT:$<STREQUAL:$<TARGET_PROPERTY:TYPE>,EXECUTABLE>>:-fsanitize=fuzzer-no-link>)
  add_link_options(-fsanitize=address,undefined)
endif()
