# The Python module `testbench` (docs/python.md): pybind11 bindings of the chi-square sampler
# tester (vectorised over NumPy arrays) and of the statistics engine, in python/.
#
# TB_BUILD_PYTHON defaults to ON when pybind11 and a Python 3 with development files, NumPy and
# (with the tests) pytest are found (Debian: pybind11-dev, python3-dev, python3-numpy,
# python3-pytest; scripts/install-deps.sh), and
# not in the sanitizer configuration (the module would need the sanitizer runtime preloaded into
# the interpreter). Debian's interpreter /usr/bin/python3 is preferred to whatever `python3` is
# first on PATH (which may lack NumPy); pass -DPython_EXECUTABLE=... to choose another.
if(NOT DEFINED Python_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python_EXECUTABLE /usr/bin/python3)
endif()
find_package(Python 3 QUIET COMPONENTS Interpreter Development.Module NumPy)
if(Python_FOUND)
  set(PYBIND11_FINDPYTHON ON)
  find_package(pybind11 2.6 CONFIG QUIET)
endif()
# The pytest suite needs pytest in that interpreter (Debian: python3-pytest).
set(tb_python_pytest FALSE)
if(Python_FOUND)
  execute_process(COMMAND ${Python_EXECUTABLE} -c "import pytest, numpy" RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
  if(rc EQUAL 0)
    set(tb_python_pytest TRUE)
  endif()
endif()
set(tb_python_default OFF)
if(Python_FOUND AND pybind11_FOUND AND (tb_python_pytest OR NOT TB_BUILD_TESTS) AND NOT TB_SANITIZE)
  set(tb_python_default ON)
endif()
option(TB_BUILD_PYTHON "Build the Python module (pybind11) and its pytest suite" ${tb_python_default})
if(TB_BUILD_PYTHON)
  if(NOT Python_FOUND OR NOT pybind11_FOUND OR (TB_BUILD_TESTS AND NOT tb_python_pytest))
    message(FATAL_ERROR "TB_BUILD_PYTHON=ON needs pybind11 and Python 3 with NumPy (and pytest for the "
                        "tests): apt-get install pybind11-dev python3-dev python3-numpy python3-pytest")
  endif()
  message(STATUS "Python module: Python ${Python_VERSION} (${Python_EXECUTABLE}), pybind11 ${pybind11_VERSION}")
  # The static layers end up inside a shared object.
  set_target_properties(tb_core tb_analytic tb_render tb_validate PROPERTIES POSITION_INDEPENDENT_CODE ON)
  add_subdirectory(python)
else()
  message(STATUS "Python module: off (TB_BUILD_PYTHON=OFF)")
endif()
