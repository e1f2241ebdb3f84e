# The README's Mitsuba lines from the command line (docs/scene.md, "Importing Mitsuba scenes"):
# `tb render` of scenes/peer/mitsuba-cornell-box.xml and of scenes/cornell-box.json (path tracer,
# 24 x 24, 16 passes of 32 spp, different seeds), then `tb compare` (Welch, alpha 0.01) must
# accept; negative control: the XML with the left wall's red albedo +5% (0.63 -> 0.6615) must be
# rejected (exit 1). Run by the CTest mitsuba_tb_compare:
#   cmake -DTB=<tb> -DSOURCE_DIR=<source tree> -DWORK=<scratch folder> -P tests/mitsuba_tb_compare.cmake
cmake_minimum_required(VERSION 3.20)
foreach(v TB SOURCE_DIR WORK)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "mitsuba_tb_compare.cmake: pass -D${v}=...")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")

function(tb expect what)
  execute_process(COMMAND "${TB}" ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${what}: exit ${rc}\n${out}")
  if(NOT rc EQUAL ${expect})
    message(FATAL_ERROR "mitsuba_tb_compare: ${what}: exit ${rc}, expected ${expect}\n${out}\n${err}")
  endif()
endfunction()

set(common --integrator pt --spp 512 --passes 16 --resolution 24x24 --no-progress)
file(READ "${SOURCE_DIR}/scenes/peer/mitsuba-cornell-box.xml" xml)
string(REPLACE "0.63, 0.065, 0.05" "0.6615, 0.065, 0.05" changed "${xml}")
if(changed STREQUAL xml)
  message(FATAL_ERROR "mitsuba_tb_compare: the left wall's albedo was not found in the XML")
endif()
file(WRITE "${WORK}/changed.xml" "${changed}")

tb(0 "render XML" render "${SOURCE_DIR}/scenes/peer/mitsuba-cornell-box.xml" ${common} --seed 11 -o "${WORK}/xml.exr")
tb(0 "render JSON" render "${SOURCE_DIR}/scenes/cornell-box.json" ${common} --seed 12 -o "${WORK}/json.exr")
tb(0 "render changed XML" render "${WORK}/changed.xml" ${common} --seed 11 -o "${WORK}/changed.exr")
tb(0 "compare XML with JSON" compare "${WORK}/xml.exr" "${WORK}/json.exr" --alpha 0.01)
tb(1 "compare changed XML with JSON (negative control)" compare "${WORK}/changed.exr" "${WORK}/json.exr" --alpha 0.01)
