# CTest python_installed_module: cmake --install --component python into PREFIX, then imports
# testbench with PYTHONPATH = PREFIX/LIBDIR/python3/dist-packages only, requires the module to
# come from there, and runs one chi-square test and its negative control (alpha = 0.01, seed 1).
cmake_minimum_required(VERSION 3.20)
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${PREFIX}" --component python
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install --component python failed (${rc})")
endif()
set(site "${PREFIX}/${LIBDIR}/python3/dist-packages")
file(GLOB module "${site}/testbench*.so")
if(NOT module)
  message(FATAL_ERROR "the module was not installed under ${site}")
endif()
set(script [=[
import os, sys
import numpy as np
import testbench as tb
site = os.path.realpath(sys.argv[1])
assert os.path.realpath(tb.__file__).startswith(site + os.sep), tb.__file__
dom = tb.Chi2Domain.interval(0.0, 1.0, 30)
good = tb.chi2_test(dom, lambda u: np.sqrt(u[:, 0]), lambda x: 2.0 * x, samples=100000, seed=1)
bad = tb.chi2_test(dom, lambda u: u[:, 0], lambda x: 2.0 * x, samples=100000, seed=1)
print("installed module", tb.__file__)
print("correct:", good.message())
print("wrong pdf (negative control):", bad.message())
sys.exit(0 if good.passed(0.01) and not bad.passed(0.01) else 1)
]=])
# Run from the prefix: `python -c` puts the working directory first on sys.path, and the test's
# own working directory is the build folder that holds the uninstalled module.
execute_process(COMMAND ${CMAKE_COMMAND} -E env "PYTHONPATH=${site}" ${PYTHON} -c "${script}" "${site}"
                WORKING_DIRECTORY "${PREFIX}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the installed module failed (${rc})")
endif()
