# `mpirun -n 3 tb render` against `tb render` in one process: for each integrator below the EXR
# (mean, Welch variance and moment channels) is byte-identical, with 5 passes cut 1 + 2 + 2 over
# the ranks. Negative control: a one-process run with --seed 2 must give a different file.
# --time under mpirun must be refused (exit 2); a rank that fails is reported by rank 0 and ends the
# run. Run by the CTest mpi_render:
#   cmake -DTB=<tb> -DMPIRUN=<mpiexec> -DSCENE=<scenes/cornell-box.json> -DWORK=<scratch> -P tests/mpi_render.cmake
cmake_minimum_required(VERSION 3.20)
foreach(v TB MPIRUN SCENE WORK)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "mpi_render.cmake: pass -D${v}=...")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
set(ENV{OMPI_ALLOW_RUN_AS_ROOT} 1)
set(ENV{OMPI_ALLOW_RUN_AS_ROOT_CONFIRM} 1)
set(common --resolution 16x16 --spp 10 --passes 5 --no-progress)

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 600)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "mpi_render: ${what}: exit ${rc}\n${out}\n${err}")
  endif()
endfunction()

foreach(integ pt lt bdpt pssmlt mmlt mlt ramlt-lens)
  run("${integ}, one process" "${TB}" render "${SCENE}" --integrator ${integ} ${common} --out "${WORK}/${integ}-1.exr")
  run("${integ}, mpirun -n 3" "${MPIRUN}" --oversubscribe -n 3 "${TB}" render "${SCENE}" --integrator ${integ} ${common}
      --out "${WORK}/${integ}-3.exr")
  file(SHA256 "${WORK}/${integ}-1.exr" one)
  file(SHA256 "${WORK}/${integ}-3.exr" three)
  if(NOT one STREQUAL three)
    message(FATAL_ERROR "mpi_render: ${integ}: the mpirun image differs from the one-process image")
  endif()
  file(READ "${WORK}/${integ}-3.json" j)
  string(JSON ranks GET "${j}" mpi_ranks)
  string(JSON passes GET "${j}" passes)
  if(NOT ranks EQUAL 3 OR NOT passes EQUAL 5)
    message(FATAL_ERROR "mpi_render: ${integ}: record says ${ranks} ranks, ${passes} passes (expected 3, 5)")
  endif()
  message("mpi_render: ${integ}: identical over 3 ranks")
endforeach()

run("pt, seed 2" "${TB}" render "${SCENE}" --integrator pt ${common} --seed 2 --out "${WORK}/pt-seed2.exr")
file(SHA256 "${WORK}/pt-1.exr" one)
file(SHA256 "${WORK}/pt-seed2.exr" seed2)
if(one STREQUAL seed2)
  message(FATAL_ERROR "mpi_render: negative control not caught: --seed 2 gives the same image as seed 1")
endif()
execute_process(COMMAND "${MPIRUN}" --oversubscribe -n 2 "${TB}" render "${SCENE}" --integrator pt --time 1
                        --no-progress --out "${WORK}/timed.exr" RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET TIMEOUT 600)
if(rc EQUAL 0)
  message(FATAL_ERROR "mpi_render: --time under mpirun was accepted")
endif()
# A rank that fails (its scene file is missing: MPMD, rank 2 is given another path) must not leave
# the others waiting: the run ends within the timeout, non-zero, rank 0 names the rank and the
# cause, and no image is written. The same with rank 0 as the failing one.
foreach(bad 2 0)
  if(bad EQUAL 2)
    set(cmd "${MPIRUN}" --oversubscribe -n 2 "${TB}" render "${SCENE}" --integrator pt ${common} --out "${WORK}/failed.exr"
            : -n 1 "${TB}" render "${WORK}/missing.json" --integrator pt ${common} --out "${WORK}/failed.exr")
  else()
    set(cmd "${MPIRUN}" --oversubscribe -n 1 "${TB}" render "${WORK}/missing.json" --integrator pt ${common} --out "${WORK}/failed.exr"
            : -n 2 "${TB}" render "${SCENE}" --integrator pt ${common} --out "${WORK}/failed.exr")
  endif()
  execute_process(COMMAND ${cmd} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
  if(rc EQUAL 0 OR NOT rc MATCHES "^[0-9]+$")
    message(FATAL_ERROR "mpi_render: rank ${bad} without its scene: exit '${rc}' (expected a non-zero exit, not a hang)\n${out}\n${err}")
  endif()
  if(NOT err MATCHES "rank ${bad} of 3 failed: cannot read")
    message(FATAL_ERROR "mpi_render: rank ${bad} without its scene: the failure is not reported by rank\n${out}\n${err}")
  endif()
  if(EXISTS "${WORK}/failed.exr")
    message(FATAL_ERROR "mpi_render: rank ${bad} without its scene: an image was written")
  endif()
endforeach()
# tb reproduce is not spread over ranks: under mpirun it is refused (exit 2, nothing written).
execute_process(COMMAND "${MPIRUN}" --oversubscribe -n 2 "${TB}" reproduce mmis-fig1 --quick --no-progress
                        --out "${WORK}/reproduce" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
if(rc EQUAL 0 OR NOT err MATCHES "tb reproduce: not spread over MPI ranks" OR EXISTS "${WORK}/reproduce/report.json")
  message(FATAL_ERROR "mpi_render: tb reproduce under mpirun was not refused (exit '${rc}')\n${out}\n${err}")
endif()
message("mpi_render: identical to one process for every integrator; --seed 2 differs (negative control caught); --time refused; "
        "a failed rank is named and ends the run; tb reproduce refused")
