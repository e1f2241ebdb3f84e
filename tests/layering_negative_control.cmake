# Negative control of cmake/CheckLayering.cmake: runs the checker on small generated source trees.
# The clean tree (downward includes in every form) must pass; each other tree adds one forbidden
# include, in one of the forms the checker must see, and must fail naming the offending file.
#   cmake -DCHECKER=<cmake/CheckLayering.cmake> -DWORK=<scratch folder> -P tests/layering_negative_control.cmake
cmake_minimum_required(VERSION 3.20)
if(NOT CHECKER OR NOT WORK)
  message(FATAL_ERROR "pass -DCHECKER=<CheckLayering.cmake> -DWORK=<scratch folder>")
endif()

# One header per folder of both layer orders, each including nothing.
set(base_files
  lib/core/c.h lib/geometry/g.h lib/material/m.h lib/light/l.h lib/camera/k.h lib/scene/s.h
  lib/film/f.h lib/path/p.h lib/differential/d.h lib/integrator/i.h lib/mcmc/x.h lib/registry/r.h
  estimators/e.h analytic/a.h validate/v.h reports/rp.h app/ap.h)

set(failures "")
set(ncases 0)

# run_case(NAME EXPECT_FAIL FILE CONTENT [NAMED]): base tree plus FILE (relative to the tree) =
# CONTENT; a rejection must name NAMED (relative to the tree; default FILE).
function(run_case name expect_fail file content)
  set(named_path "${file}")
  if(ARGC GREATER 4)
    set(named_path "${ARGV4}")
  endif()
  set(tree "${WORK}/${name}")
  file(REMOVE_RECURSE "${tree}")
  foreach(b IN LISTS base_files)
    file(WRITE "${tree}/${b}" "#pragma once\n")
  endforeach()
  if(file)
    file(WRITE "${tree}/${file}" "${content}")
  endif()
  execute_process(COMMAND "${CMAKE_COMMAND}" "-DROOT=${tree}" -P "${CHECKER}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  math(EXPR n "${ncases} + 1")
  set(ncases ${n} PARENT_SCOPE)
  if(expect_fail)
    string(FIND "${err}" "${tree}/${named_path}" named)
    if(rc EQUAL 0 OR named LESS 0)
      set(failures "${failures}${name}: expected the checker to reject ${named_path} (exit ${rc})\n${out}${err}\n"
          PARENT_SCOPE)
    endif()
  elseif(NOT rc EQUAL 0)
    set(failures "${failures}${name}: expected the checker to pass (exit ${rc})\n${out}${err}\n" PARENT_SCOPE)
  endif()
endfunction()

# Clean: every form of include, downward or within a folder, and higher folders named in prose.
run_case(clean FALSE lib/registry/all.cpp [=[
#include "lib/registry/r.h"
#include "r.h"
  #include "lib/mcmc/x.h"
	#include <lib/integrator/i.h>
# include "lib/differential/d.h"
#	 include	"lib/path/p.h"
#if defined(TB_SOMETHING) && __has_include(<lib/film/f.h>)
#  include <lib/film/f.h>
#endif
/* c */ #include "../scene/s.h"
#include_next <lib/camera/k.h>
#include \
  "lib/light/l.h"
#define TB_HEADER "lib/material/m.h"
#include TB_HEADER
#include "lib/geometry/g.h"
#include "lib/core/c.h"
#include "estimators/e.h"
#include <vector>
// Registers what lib/registry/ lists; validate/ and app/ use it.
]=])
run_case(clean_peers_and_order FALSE lib/mcmc/ok.h [=[
#include "lib/integrator/i.h"
#include "lib/differential/d.h"
#include "lib/path/p.h"
#include "lib/film/f.h"
]=])
run_case(clean_top FALSE app/ok.cpp [=[
#include "reports/rp.h"
#include "validate/v.h"
#include "analytic/a.h"
#include "lib/registry/r.h"
#include "estimators/e.h"
#include "lib/core/c.h"
]=])

# Forbidden includes inside lib/, one form each.
run_case(plain TRUE lib/integrator/up.cpp "#include \"lib/mcmc/x.h\"\n")
run_case(leading_spaces TRUE lib/geometry/up.h "   #include \"lib/scene/s.h\"\n")
run_case(leading_tab TRUE lib/geometry/up.h "\t#include \"lib/material/m.h\"\n")
run_case(hash_space TRUE lib/scene/up.h "# include \"lib/film/f.h\"\n")
run_case(hash_tabs TRUE lib/film/up.h "#\t include\t\"lib/path/p.h\"\n")
run_case(angle TRUE lib/mcmc/up.h "#include <lib/registry/r.h>\n")
run_case(angle_indented_hash_space TRUE lib/path/up.h "  #  include <lib/integrator/i.h>\n")
run_case(in_if_block TRUE lib/integrator/up.h [=[
#if defined(TB_WITH_MCMC)
#  include "lib/mcmc/x.h"
#else
#  include "lib/path/p.h"
#endif
]=])
run_case(in_if0_block TRUE lib/integrator/up.h "#if 0\n#include \"lib/registry/r.h\"\n#endif\n")
run_case(after_comment TRUE lib/integrator/up.h "#if 1\n/* mcmc */ #include \"lib/mcmc/x.h\"\n#endif\n")
run_case(after_code TRUE lib/integrator/up.cpp "#if 1\nint tb_a = 0; #include <lib/mcmc/x.h>\n#endif\n")
run_case(has_include TRUE lib/integrator/up.h "#if __has_include(\"lib/mcmc/x.h\")\n#endif\n")
run_case(has_include_angle TRUE lib/geometry/up.h
         "#if defined(A) && __has_include( <lib/camera/k.h> )\n#endif\n")
run_case(include_next TRUE lib/integrator/up.h "#include_next <lib/mcmc/x.h>\n")
run_case(import TRUE lib/integrator/up.h "#import \"lib/mcmc/x.h\"\n")
run_case(splice_after_hash TRUE lib/integrator/up.h "#\\\ninclude \"lib/mcmc/x.h\"\n")
run_case(splice_before_path TRUE lib/integrator/up.h "#include \\\r\n  <lib/mcmc/x.h>\r\n")
run_case(crlf TRUE lib/integrator/up.h "#pragma once\r\n#include \"lib/mcmc/x.h\"\r\n")
run_case(relative TRUE lib/integrator/up.cpp "#include \"../mcmc/x.h\"\n")
run_case(relative_dot TRUE lib/integrator/up.cpp "#include \"./../registry/r.h\"\n")
run_case(relative_deep TRUE lib/core/up.h "#include \"../../validate/v.h\"\n")
run_case(double_slash TRUE lib/integrator/up.cpp "#include \"lib//mcmc/x.h\"\n")
run_case(computed TRUE lib/integrator/up.cpp "#define TB_H \"lib/mcmc/x.h\"\n#include TB_H\n")
run_case(commented_out TRUE lib/integrator/up.cpp "// #include \"lib/mcmc/x.h\"\n")
run_case(hpp_file TRUE lib/core/up.hpp "#include \"lib/geometry/g.h\"\n")
run_case(inl_file TRUE lib/geometry/up.inl "#include \"lib/light/l.h\"\n")
run_case(extensionless_target TRUE lib/integrator/up.h "#include \"lib/mcmc/x\"\n")
# The level of material, light and camera: peers, none includes another.
run_case(peer_light_material TRUE lib/light/up.h "#include \"lib/material/m.h\"\n")
run_case(peer_camera_light TRUE lib/camera/up.h "#include <lib/light/l.h>\n")
run_case(peer_material_camera TRUE lib/material/up.cpp "#include \"../camera/k.h\"\n")
# lib/differential between lib/path and lib/integrator.
run_case(path_differential TRUE lib/path/up.h "#include \"lib/differential/d.h\"\n")
run_case(differential_integrator TRUE lib/differential/up.h "#include \"lib/integrator/i.h\"\n")
# A folder of lib/ without a level.
run_case(unranked_folder TRUE lib/newfolder/n.h "#pragma once\n" lib/newfolder)
run_case(unranked_target TRUE lib/scene/up.h "#include \"lib/newfolder/n.h\"\n")
# Top-level order.
run_case(core_estimators TRUE lib/core/up.h "  # include <estimators/e.h>\n")
run_case(estimators_analytic TRUE estimators/up.h "#include \"analytic/a.h\"\n")
run_case(analytic_lib TRUE analytic/up.h "#include <lib/scene/s.h>\n")
run_case(lib_analytic TRUE lib/scene/up.cpp "#include \"analytic/a.h\"\n")
run_case(lib_validate TRUE lib/registry/up.cpp "#include \"../../validate/v.h\"\n")
run_case(validate_reports TRUE validate/up.h "#include \"reports/rp.h\"\n")
run_case(reports_app TRUE reports/up.h "#if __has_include(<app/ap.h>)\n#endif\n")

if(failures)
  message(FATAL_ERROR "layering negative control:\n${failures}")
endif()
message(STATUS "layering negative control: ${ncases} trees as expected")
