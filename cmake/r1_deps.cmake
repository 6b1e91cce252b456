# Third-party packages, all from Debian (scripts/install-deps.sh installs them).
find_package(Threads REQUIRED)
find_package(TBB REQUIRED)
find_package(tomlplusplus REQUIRED)
find_package(Boost 1.74 REQUIRED)
find_package(CLI11 QUIET CONFIG)
if(NOT TARGET CLI11::CLI11)
  # Debian's CLI11 2.1 ships only the header; wrap it.
  find_path(CLI11_INCLUDE_DIR CLI/CLI.hpp REQUIRED)
  add_library(CLI11::CLI11 INTERFACE IMPORTED)
  target_include_directories(CLI11::CLI11 INTERFACE ${CLI11_INCLUDE_DIR})
endif()
find_package(nlohmann_json 3 REQUIRED)
# SHA-256 of the snapshot's record chunks (R1-EPO-017): OpenSSL's libcrypto.
find_package(OpenSSL 3 REQUIRED COMPONENTS Crypto)
# The layout graph's arrays held compressed during the spectral solve (R1-EPO-006): zstd.
find_package(zstd 1.4 REQUIRED CONFIG)
if(R1_BUILD_TESTS)
  find_package(GTest REQUIRED)
  find_package(rapidcheck REQUIRED)
endif()
if(R1_BUILD_BENCH AND NOT R1_SANITIZE AND NOT R1_FUZZ)
  find_package(benchmark REQUIRED)
endif()
# The frame renderer's images: OpenImageIO (EXR, PNG, text) and OpenColorIO (display transform).
find_package(OpenImageIO 2.4 REQUIRED CONFIG)
# Debian 12's OpenColorIO CMake package file sits in /usr/share/cmake and computes a wrong prefix
# ("/include"); its pkg-config file is right, so use that.
find_package(PkgConfig REQUIRED)
pkg_check_modules(R1_OCIO REQUIRED IMPORTED_TARGET OpenColorIO>=2.1)
add_library(OpenColorIO::OpenColorIO ALIAS PkgConfig::R1_OCIO)
