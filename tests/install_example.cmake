# The installed package, used from outside (docs/install.md). Run by the CTest install_example:
#   cmake -DBUILD_DIR=<build tree> -DSOURCE_DIR=<source tree> -DWORK=<scratch folder>
#         -DGENERATOR=<generator> -DCXX_COMPILER=<c++> [-DLAUNCHER=<ccache>] -P tests/install_example.cmake
# 1. cmake --install BUILD_DIR --prefix WORK/prefix (exactly the documented command);
# 2. a project asking for find_package(testbench 1.0) must NOT find 0.x (the version file works),
#    and one asking for the installed major.minor must;
# 3. a project with one program per lower target (testbench::core, ::estimators, ::analytic,
#    ::render), each linking only that target, builds and runs (each target stands alone);
# 4. configures examples/own-sampler against WORK/prefix only (no package registry, no build
#    tree), requires testbench_DIR to be the installed one and no include path into the sources;
# 5. builds it with -Werror and runs it: it exits non-zero when an assertion or a negative
#    control misbehaves.
cmake_minimum_required(VERSION 3.20)
foreach(v BUILD_DIR SOURCE_DIR WORK GENERATOR CXX_COMPILER)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "install_example.cmake: pass -D${v}=...")
  endif()
endforeach()

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "install_example: ${what} failed (${rc}):\n${err}")
  endif()
endfunction()

file(REMOVE_RECURSE "${WORK}")
set(prefix "${WORK}/prefix")
run("cmake --install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}")
foreach(f include/validate/stats/tests.h include/validate/chi2/sampler_chi2.h include/estimators/mis.h
          include/lib/core/rng.h lib/libtb_validate.a lib/cmake/testbench/testbenchConfig.cmake
          lib/cmake/testbench/testbenchConfigVersion.cmake lib/cmake/testbench/testbenchTargets.cmake)
  if(NOT EXISTS "${prefix}/${f}")
    message(FATAL_ERROR "install_example: ${prefix}/${f} was not installed")
  endif()
endforeach()

set(common -G "${GENERATOR}" -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_PREFIX_PATH=${prefix}
           -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON
           -DCMAKE_BUILD_TYPE=Release)
if(LAUNCHER)
  list(APPEND common -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()

# Version requests: 1.0 must be refused, the installed major.minor accepted.
file(READ "${prefix}/lib/cmake/testbench/testbenchConfigVersion.cmake" version_file)
string(REGEX MATCH "set\\(PACKAGE_VERSION \"([0-9]+\\.[0-9]+)" _ "${version_file}")
set(installed_mm "${CMAKE_MATCH_1}")
foreach(request IN ITEMS 1.0 ${installed_mm})
  set(dir "${WORK}/version-${request}")
  file(MAKE_DIRECTORY "${dir}")
  file(WRITE "${dir}/CMakeLists.txt"
       "cmake_minimum_required(VERSION 3.20)\nproject(version_request LANGUAGES CXX)\n"
       "find_package(testbench ${request} REQUIRED)\n")
  execute_process(COMMAND ${CMAKE_COMMAND} -S "${dir}" -B "${dir}/build" ${common}
                  RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
  if(request STREQUAL "1.0" AND rc EQUAL 0)
    message(FATAL_ERROR "install_example: find_package(testbench 1.0) accepted version ${installed_mm}")
  elseif(NOT request STREQUAL "1.0" AND NOT rc EQUAL 0)
    message(FATAL_ERROR "install_example: find_package(testbench ${request}) failed on the installed package")
  endif()
  message("find_package(testbench ${request}): result ${rc} (as expected)")
endforeach()

# One program per lower target; each exits non-zero if its check fails.
set(dir "${WORK}/targets")
file(MAKE_DIRECTORY "${dir}")
file(WRITE "${dir}/core.cpp" [=[
#include <vector>
#include "lib/core/discrete.h"
#include "lib/core/strict_json.h"
int main() {
  const std::vector<double> w{1.0, 3.0};
  const auto t = tb::AliasTable::create(w);
  return t && t->pmf(1) == 0.75 && tb::edit_distance("kitten", "sitting") == 3 ? 0 : 1;
}
]=])
file(WRITE "${dir}/estimators.cpp" [=[
#include <optional>
#include "estimators/mc.h"
struct Unit {  // uniform on [0, 1]
  using Sample = double;
  std::optional<double> sample(tb::Uniforms& u) const { return u.next(); }
  double pdf(double) const { return 1.0; }
};
int main() {
  tb::FixedUniforms u{0.25, 0.75};
  return tb::estimate_mc([](double x) { return x; }, Unit{}, 2, u).value == 0.5 ? 0 : 1;
}
]=])
file(WRITE "${dir}/analytic.cpp" [=[
#include <cmath>
#include "analytic/integrands.h"
int main() {
  if (tb::integrands_1d().empty()) return 1;
  for (const auto& f : tb::integrands_1d())
    if (!std::isfinite(f.integral)) return 1;
  return 0;
}
]=])
file(WRITE "${dir}/render.cpp" [=[
#include <exception>
#include "lib/scene/scene_loader.h"
int main() {
  try {
    tb::load_world_from_string("{", "truncated");
  } catch (const std::exception&) {
    return 0;  // a parse error, reported by the scene loader
  }
  return 1;
}
]=])
file(WRITE "${dir}/CMakeLists.txt" [=[
cmake_minimum_required(VERSION 3.20)
project(targets LANGUAGES CXX)
find_package(testbench REQUIRED)
foreach(t core estimators analytic render)
  add_executable(${t}_only ${t}.cpp)
  target_link_libraries(${t}_only PRIVATE testbench::${t})
  target_compile_options(${t}_only PRIVATE -Wall -Wextra -Werror)
endforeach()
]=])
run("configuring the per-target programs" ${CMAKE_COMMAND} -S "${dir}" -B "${dir}/build" ${common})
run("building the per-target programs" ${CMAKE_COMMAND} --build "${dir}/build" -j 2)
foreach(t core estimators analytic render)
  run("running ${t}_only" "${dir}/build/${t}_only")
  message("testbench::${t} alone: ok")
endforeach()

set(example "${WORK}/own-sampler")
run("configuring examples/own-sampler" ${CMAKE_COMMAND} -S "${SOURCE_DIR}/examples/own-sampler" -B "${example}"
    ${common} -DOWN_SAMPLER_WERROR=ON -DCMAKE_EXPORT_COMPILE_COMMANDS=ON)
file(STRINGS "${example}/CMakeCache.txt" found REGEX "^testbench_DIR:")
if(NOT found STREQUAL "testbench_DIR:PATH=${prefix}/lib/cmake/testbench")
  message(FATAL_ERROR "install_example: the example found '${found}', not the installed package under ${prefix}")
endif()
file(READ "${example}/compile_commands.json" commands)
string(FIND "${commands}" "${prefix}/include" at_prefix)
if(at_prefix EQUAL -1)
  message(FATAL_ERROR "install_example: the example does not compile against ${prefix}/include:\n${commands}")
endif()
foreach(flag -I -isystem)
  foreach(sep " " "")
    string(FIND "${commands}" "${flag}${sep}${SOURCE_DIR} " at_source)
    if(NOT at_source EQUAL -1)
      message(FATAL_ERROR "install_example: the example includes the source tree:\n${commands}")
    endif()
  endforeach()
endforeach()
run("building examples/own-sampler" ${CMAKE_COMMAND} --build "${example}" -j 2)
run("running own_sampler" "${example}/own_sampler")
