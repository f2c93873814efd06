# Every dependency is a Debian package (scripts/install_deps.sh installs them).
# Nothing is vendored or downloaded at build time.
find_package(OpenMP REQUIRED)
find_package(HDF5 REQUIRED COMPONENTS C)
find_package(TIFF REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(fmt REQUIRED)
find_package(tomlplusplus REQUIRED)
# OpenCV: calib3d for estimateAffine3D (track/registration.cpp, the RANSAC map between stages).
find_package(OpenCV REQUIRED COMPONENTS core calib3d)
# CGAL first, then Eigen with NO_MODULE: CGAL's own FindEigen3 module would
# otherwise shadow Eigen's config and no Eigen3::Eigen target would exist.
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)  # Debug is only for the sanitizer build
find_package(CGAL QUIET)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
if(TOMOGRAIN_TESTS)
  find_package(GTest REQUIRED)
endif()
if(TOMOGRAIN_BENCH)
  find_package(benchmark REQUIRED)
endif()
# xxHash: content hashes of a study's inputs (study/records.cpp), seconds for a 3.6 GB scan.
find_package(PkgConfig REQUIRED)
pkg_check_modules(XXHASH REQUIRED IMPORTED_TARGET libxxhash)
# libdeflate: HDF5 chunks (de)compressed in zlib's format, 2-3x zlib's speed
# with a vectorised Adler-32 (core/io/hdf5_chunks.cpp).
pkg_check_modules(LIBDEFLATE REQUIRED IMPORTED_TARGET libdeflate)
