# Finds the OpenCV modules this project uses from Debian's per-module packages
# (libopencv-core-dev, libopencv-imgproc-dev, libopencv-imgcodecs-dev). Those packages ship
# headers and libraries but no CMake package file (only the whole libopencv-dev does), so this
# creates the imported targets OpenCV::core, OpenCV::imgproc and OpenCV::imgcodecs itself.
find_path(OpenCVModules_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
set(_opencv_targets)
foreach(_module IN ITEMS core imgproc imgcodecs)
  find_library(OpenCVModules_${_module}_LIBRARY NAMES opencv_${_module})
  list(APPEND _opencv_targets OpenCVModules_${_module}_LIBRARY)
endforeach()

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenCVModules REQUIRED_VARS OpenCVModules_INCLUDE_DIR ${_opencv_targets})

if(OpenCVModules_FOUND)
  foreach(_module IN ITEMS core imgproc imgcodecs)
    if(NOT TARGET OpenCV::${_module})
      add_library(OpenCV::${_module} UNKNOWN IMPORTED)
      set_target_properties(OpenCV::${_module} PROPERTIES
        IMPORTED_LOCATION "${OpenCVModules_${_module}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${OpenCVModules_INCLUDE_DIR}")
    endif()
  endforeach()
  set_property(TARGET OpenCV::imgproc APPEND PROPERTY INTERFACE_LINK_LIBRARIES OpenCV::core)
  set_property(TARGET OpenCV::imgcodecs APPEND PROPERTY INTERFACE_LINK_LIBRARIES OpenCV::imgproc)
endif()
