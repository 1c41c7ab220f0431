# Passed as -DCMAKE_PROJECT_INCLUDE=... by build_msgs.sh, never part of msgs/CMakeLists.txt:
# works around quirk 2 of the PyPI `ros-jazzy-*` wheels (../../../shared/design/
# ros2-jazzy-wheels.md). Their exported `<pkg>__rosidl_generator_py` targets carry the wheel
# builder's Python and NumPy include directories (/opt/python/cp311-cp311/...), and CMake's
# generate step stops with "Imported target ... includes non-existent path". Once the package's
# CMakeLists.txt has been read (so every find_package has imported its targets), re-point those
# targets at this interpreter's include directories.

find_package(Python3 REQUIRED COMPONENTS Interpreter)
execute_process(
  COMMAND "${Python3_EXECUTABLE}" -c
    "import sysconfig, numpy; print(sysconfig.get_paths()['include'] + ';' + numpy.get_include())"
  OUTPUT_VARIABLE _jazzy_wheels_py_includes
  OUTPUT_STRIP_TRAILING_WHITESPACE
  COMMAND_ERROR_IS_FATAL ANY)

function(_jazzy_wheels_repoint_python_includes)
  get_property(_targets DIRECTORY "${CMAKE_SOURCE_DIR}" PROPERTY IMPORTED_TARGETS)
  set(_fixed "")
  foreach(_target IN LISTS _targets)
    if(NOT _target MATCHES "__rosidl_generator_py$")
      continue()
    endif()
    get_target_property(_dirs ${_target} INTERFACE_INCLUDE_DIRECTORIES)
    if(_dirs AND _dirs MATCHES "^/opt/python/|;/opt/python/")
      list(FILTER _dirs EXCLUDE REGEX "^/opt/python/")
      list(APPEND _dirs ${_jazzy_wheels_py_includes})
      set_target_properties(${_target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_dirs}")
      list(APPEND _fixed ${_target})
    endif()
  endforeach()
  list(LENGTH _fixed _count)
  message(STATUS "jazzy_wheels.cmake: re-pointed the Python include directories of ${_count} imported targets")
endfunction()

cmake_language(DEFER DIRECTORY "${CMAKE_SOURCE_DIR}" CALL _jazzy_wheels_repoint_python_includes)
