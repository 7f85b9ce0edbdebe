# SPDX-License-Identifier: MIT
# Third-party packages, found once. CMake names verified in ../shared/PLATFORM.md.
find_package(Threads REQUIRED)
find_package(glm REQUIRED)
# Config-mode first: OpenVDB's module folder ships FindTBB/FindOpenEXR that would shadow these.
find_package(TBB CONFIG REQUIRED)
find_package(OpenEXR CONFIG REQUIRED)
find_package(PNG REQUIRED)
# zlib: the mesh importer inflates compressed VTK XML arrays to check them (Debian zlib1g-dev).
find_package(ZLIB REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
# Eigen: the dense linear algebra of the half-space solver (lucent/dipole/HalfSpace.h).
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(embree 3 REQUIRED)
find_package(OpenMesh REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(EPOXY REQUIRED IMPORTED_TARGET epoxy)
find_package(OpenGL REQUIRED COMPONENTS EGL)
find_package(VTK 9.1 REQUIRED COMPONENTS CommonCore CommonDataModel FiltersCore FiltersGeneral
    FiltersSources FiltersModeling IOGeometry IOPLY IOLegacy IOXML)
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB)
find_package(OpenVDB REQUIRED COMPONENTS openvdb)
if(LUCENT_BUILD_GUI)
    find_package(Qt6 REQUIRED COMPONENTS Core Gui Widgets OpenGL OpenGLWidgets Test Charts)
endif()
if(LUCENT_BUILD_TESTS)
    find_package(GTest REQUIRED)
endif()
if(LUCENT_BUILD_BENCHMARKS)
    find_package(benchmark REQUIRED)
endif()
