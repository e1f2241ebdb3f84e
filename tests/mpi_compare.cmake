# `mpirun -n 2 tb compare SCENE --integrators pt,bdpt ...`: the 7 renders (reference and 2 x 3
# checkpoints) are dealt over the ranks, every file arrives in DIR on rank 0 and the report is
# written; a one-process `--resume` on DIR then reloads all 7 (same settings, seeds and keys as one
# process would use). Negative control: `--resume` with --seed 2 must reload none of them.
#   cmake -DTB=<tb> -DMPIRUN=<mpiexec> -DSCENE=<scenes/cornell-box.json> -DWORK=<scratch> -P tests/mpi_compare.cmake
cmake_minimum_required(VERSION 3.20)
foreach(v TB MPIRUN SCENE WORK)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "mpi_compare.cmake: pass -D${v}=...")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK}")
set(ENV{OMPI_ALLOW_RUN_AS_ROOT} 1)
set(ENV{OMPI_ALLOW_RUN_AS_ROOT_CONFIRM} 1)
set(common compare "${SCENE}" --integrators pt,bdpt --time 0.3 --checkpoints 3 --resolution 16x16 --threads 1
    --no-progress -o "${WORK}/out")

function(run what var)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 600)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "mpi_compare: ${what}: exit ${rc}\n${out}\n${err}")
  endif()
  set(${var} "${out}" PARENT_SCOPE)
endfunction()

run("mpirun -n 2" mpi "${MPIRUN}" --oversubscribe -n 2 "${TB}" ${common})
if(NOT mpi MATCHES "under mpirun: 7 renders over 2 ranks \\(7 done, 0 lost")
  message(FATAL_ERROR "mpi_compare: expected 7 renders done over 2 ranks:\n${mpi}")
endif()
foreach(f reference.exr runs/pt-2.exr runs/bdpt-1.json results.json index.html)
  if(NOT EXISTS "${WORK}/out/${f}")
    message(FATAL_ERROR "mpi_compare: ${f} missing after the mpirun")
  endif()
endforeach()
run("one process, --resume" again "${TB}" ${common} --resume)
string(REGEX MATCHALL "\\(resumed\\)" hits "${again}")
list(LENGTH hits n)
if(NOT n EQUAL 7)
  message(FATAL_ERROR "mpi_compare: --resume reloaded ${n} of 7 renders:\n${again}")
endif()
run("one process, --resume --seed 2" other "${TB}" ${common} --resume --seed 2)
string(REGEX MATCHALL "\\(resumed\\)" hits2 "${other}")
list(LENGTH hits2 n2)
if(NOT n2 EQUAL 0)
  message(FATAL_ERROR "mpi_compare: negative control not caught: --seed 2 reloaded ${n2} renders")
endif()
# A rank that cannot read the scene (MPMD: rank 1 is given a missing file) must not hang the run:
# rank 0 names it, renders its items itself and the comparison completes.
set(rest --integrators pt,bdpt --time 0.3 --checkpoints 3 --resolution 16x16 --threads 1 --no-progress -o "${WORK}/failed")
execute_process(COMMAND "${MPIRUN}" --oversubscribe -n 1 "${TB}" compare "${SCENE}" ${rest}
                        : -n 1 "${TB}" compare "${WORK}/missing.json" ${rest}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 600)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "mpi_compare: rank 1 without its scene: exit '${rc}'\n${out}\n${err}")
endif()
if(NOT err MATCHES "rank 1 of 2 failed \\(cannot read" OR NOT out MATCHES "\\(4 done, 3 lost and rendered again on rank 0\\)")
  message(FATAL_ERROR "mpi_compare: rank 1 without its scene: failure not reported, or its 3 renders not redone\n${out}\n${err}")
endif()
if(NOT EXISTS "${WORK}/failed/runs/bdpt-2.exr" OR NOT EXISTS "${WORK}/failed/results.json")
  message(FATAL_ERROR "mpi_compare: rank 1 without its scene: the comparison did not complete")
endif()
message("mpi_compare: 7 renders over 2 ranks, all reloaded by a one-process --resume; --seed 2 reloads none; "
        "a rank without its scene is named and its renders redone on rank 0")
