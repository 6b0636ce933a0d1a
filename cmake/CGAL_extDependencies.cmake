# Finds what the CGAL_ext headers need; shared by the build tree and the installed package config.
find_package(CGAL 5.5 REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
include(CGAL_Eigen3_support)
find_package(TBB QUIET)
include(CGAL_TBB_support)
if(NOT TARGET CGAL::TBB_support)
  # Sequential fallback: CGAL_ext still works, Parallel_if_available_tag means sequential.
  add_library(CGAL::TBB_support INTERFACE IMPORTED)
endif()

# CHOLMOD (SuiteSparse) for the supernodal Cholesky of the least-squares solves; optional: without it the
# solves use Eigen's SimplicialLDLT. Debian's SuiteSparse 5 ships no CMake package, so look for the files.
option(CGAL_EXT_USE_CHOLMOD "Use SuiteSparse CHOLMOD for sparse Cholesky factorisations when found" ON)
if(CGAL_EXT_USE_CHOLMOD AND NOT TARGET SuiteSparse::CHOLMOD)
  find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
  find_library(CHOLMOD_LIBRARY cholmod)
  # CHOLMOD's headers declare SuiteSparse_config (its allocator, which the tests replace), defined here.
  find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig)
  if(CHOLMOD_INCLUDE_DIR AND CHOLMOD_LIBRARY AND SUITESPARSE_CONFIG_LIBRARY)
    add_library(SuiteSparse::CHOLMOD INTERFACE IMPORTED)
    set_target_properties(SuiteSparse::CHOLMOD PROPERTIES
      INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
      INTERFACE_LINK_LIBRARIES "${CHOLMOD_LIBRARY};${SUITESPARSE_CONFIG_LIBRARY}"
      INTERFACE_COMPILE_DEFINITIONS CGAL_EXT_USE_CHOLMOD)
  endif()
endif()
if(NOT TARGET SuiteSparse::CHOLMOD)
  add_library(SuiteSparse::CHOLMOD INTERFACE IMPORTED) # empty: Eigen's own Cholesky is used
endif()
