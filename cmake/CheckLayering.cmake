# Fails when a lower layer includes a higher one (ARCHITECTURE.md: nothing includes upward).
# Layer order: lib/core < estimators < {analytic, lib/<render folders>} < validate < reports < app.
set(rules
  "lib/core|estimators/,analytic/,lib/geometry/,lib/material/,lib/light/,lib/camera/,lib/scene/,lib/film/,lib/path/,lib/integrator/,lib/mcmc/,lib/differential/,validate/,reports/,app/"
  "estimators|analytic/,lib/geometry/,lib/material/,lib/light/,lib/camera/,lib/scene/,lib/film/,lib/path/,lib/integrator/,lib/mcmc/,lib/differential/,validate/,reports/,app/"
  "analytic|lib/geometry/,lib/material/,lib/light/,lib/camera/,lib/scene/,lib/film/,lib/path/,lib/integrator/,lib/mcmc/,lib/differential/,validate/,reports/,app/"
  "lib|analytic/,validate/,reports/,app/"
  "validate|reports/,app/"
  "reports|app/")
set(bad "")
foreach(rule IN LISTS rules)
  string(REPLACE "|" ";" parts "${rule}")
  list(GET parts 0 folder)
  list(GET parts 1 fb_csv)
  string(REPLACE "," ";" forbidden "${fb_csv}")
  file(GLOB_RECURSE files ${ROOT}/${folder}/*.h ${ROOT}/${folder}/*.cpp)
  foreach(f IN LISTS files)
    file(STRINGS ${f} incs REGEX "^#include \"")
    foreach(inc IN LISTS incs)
      foreach(fb IN LISTS forbidden)
        if(inc MATCHES "^#include \"${fb}")
          string(APPEND bad "${f}: ${inc}\n")
        endif()
      endforeach()
    endforeach()
  endforeach()
endforeach()
if(bad)
  message(FATAL_ERROR "Upward includes:\n${bad}")
endif()
message(STATUS "layering: no upward includes")
