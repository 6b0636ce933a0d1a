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
