# Fails when a layer includes a higher one or a peer (docs/overview.md, "Layers"). Run as
#   cmake -DROOT=<source tree> -P cmake/CheckLayering.cmake
#
# Two orders, each a list of levels from the bottom up; a level is a comma-separated set of folders.
# A file may include its own folder and the folders of lower levels, never a higher level, and never
# another folder of its own level (folders of one level are peers), unless the pair is listed in
# the allowed peer includes below.
#
# Top level: lib/core < estimators < {analytic, lib/ renderer folders} < validate < reports < app.
# "lib/" stands for every folder of lib/ except lib/core (the longest matching prefix wins).
set(top_levels "lib/core" "estimators" "analytic,lib" "validate" "reports" "app")
# Inside lib/: every folder of lib/ must appear here (a new folder has to be given a level).
set(lib_levels
  "lib/core" "lib/geometry" "lib/material,lib/light,lib/camera" "lib/scene" "lib/film" "lib/path"
  "lib/differential" "lib/integrator" "lib/mcmc" "lib/registry")
# Peer includes that are allowed, as "from>to" (none: material, light and camera need none today).
set(allowed_peer_includes "")
#
# What counts as an include (after joining backslash-continued lines; matched anywhere on a line,
# so also after a comment or other code, in any #if branch, and in commented-out code):
#   #include / #include_next / #import, with any whitespace around '#', "..." or <...>;
#   __has_include(...) / __has_include_next(...);
#   any "..." or <...> naming a header (.h .hh .hpp .hxx .inl .ipp .tpp .inc), which catches
#   computed includes (#define HEADER "lib/x/y.h" ... #include HEADER).
# A quoted path that starts with ./ or ../, or names a file next to the including file, is resolved
# against the including file's folder; every other path against ROOT (the only include directory).

cmake_minimum_required(VERSION 3.20)
if(NOT ROOT)
  message(FATAL_ERROR "CheckLayering.cmake: pass -DROOT=<source tree>")
endif()
cmake_path(ABSOLUTE_PATH ROOT NORMALIZE)
string(REGEX REPLACE "/$" "" ROOT "${ROOT}")

# Sets <out_level> and <out_unit> to the level index and folder of <path> (relative to ROOT) in
# <levels>; -1 and "" if no folder of <levels> is a prefix of it. The longest prefix wins.
function(classify path levels out_level out_unit)
  set(best_level -1)
  set(best_unit "")
  set(best_len 0)
  set(i 0)
  foreach(level IN LISTS levels)
    string(REPLACE "," ";" units "${level}")
    foreach(u IN LISTS units)
      string(FIND "${path}" "${u}/" pos)
      string(LENGTH "${u}" len)
      if(pos EQUAL 0 AND len GREATER best_len)
        set(best_level ${i})
        set(best_unit "${u}")
        set(best_len ${len})
      endif()
    endforeach()
    math(EXPR i "${i} + 1")
  endforeach()
  set(${out_level} ${best_level} PARENT_SCOPE)
  set(${out_unit} "${best_unit}" PARENT_SCOPE)
endfunction()

# Appends to <out_var> a line per forbidden include of <from> -> <to> under <levels>.
function(check_pair rel to levels text out_var)
  classify("${rel}" "${levels}" fl fu)
  classify("${to}" "${levels}" tl tu)
  if(fl LESS 0 OR tl LESS 0 OR fu STREQUAL tu OR tl LESS fl)
    return()
  endif()
  if(tl EQUAL fl AND "${fu}>${tu}" IN_LIST allowed_peer_includes)
    return()
  endif()
  if(tl EQUAL fl)
    set(why "peer folder of the same level")
  else()
    set(why "higher layer")
  endif()
  set(${out_var} "${${out_var}}${ROOT}/${rel}: ${text}  (${fu} -> ${tu}: ${why})\n" PARENT_SCOPE)
endfunction()

set(ext "h|hh|hpp|hxx|inl|ipp|tpp|inc")
set(re_directive "#[ \t]*(include_next|include|import)[ \t]*[<\"][^\">;\n]*[\">]")
set(re_has_include "__has_include(_next)?[ \t]*\\([ \t]*[<\"][^\">;\n]*[\">]")
set(re_header_name "[<\"][^\"<>; \t\n]*\\.(${ext})[\">]")

set(bad "")
set(globs "")
foreach(d lib estimators analytic validate reports app)
  foreach(e cpp cc cxx ${ext})
    string(REPLACE "|" ";" exts "${e}")
    foreach(x IN LISTS exts)
      list(APPEND globs "${ROOT}/${d}/*.${x}")
    endforeach()
  endforeach()
endforeach()
file(GLOB_RECURSE files ${globs})
list(REMOVE_DUPLICATES files)

# Every folder of lib/ needs a level of its own.
file(GLOB lib_children LIST_DIRECTORIES true "${ROOT}/lib/*")
foreach(c IN LISTS lib_children)
  if(IS_DIRECTORY "${c}")
    file(RELATIVE_PATH crel "${ROOT}" "${c}")
    classify("${crel}/" "${lib_levels}" cl cu)
    if(NOT cu STREQUAL crel)
      string(APPEND bad "${c}: folder of lib/ without a level (add it to lib_levels)\n")
    endif()
  endif()
endforeach()

foreach(f IN LISTS files)
  file(RELATIVE_PATH rel "${ROOT}" "${f}")
  get_filename_component(dir "${f}" DIRECTORY)
  file(READ "${f}" text)
  # Backslash-newline splices lines before the preprocessor sees directives.
  string(REGEX REPLACE "\\\\\r?\n" "" text "${text}")
  string(REGEX MATCHALL "${re_directive}" m1 "${text}")
  string(REGEX MATCHALL "${re_has_include}" m2 "${text}")
  string(REGEX MATCHALL "${re_header_name}" m3 "${text}")
  set(seen "")
  foreach(m IN LISTS m1 m2 m3)
    string(REGEX MATCH "([<\"])([^\">\n]*)[\">]$" _ "${m}")
    set(delim "${CMAKE_MATCH_1}")
    string(STRIP "${CMAKE_MATCH_2}" p)
    if(p STREQUAL "")
      continue()
    endif()
    set(resolved "")
    if(delim STREQUAL "\"" AND (p MATCHES "^\\.\\.?/" OR EXISTS "${dir}/${p}"))
      set(resolved "${dir}/${p}")
    else()
      set(resolved "${ROOT}/${p}")
    endif()
    cmake_path(NORMAL_PATH resolved)
    string(FIND "${resolved}" "${ROOT}/" pos)
    if(NOT pos EQUAL 0)
      continue()
    endif()
    file(RELATIVE_PATH to "${ROOT}" "${resolved}")
    if(to IN_LIST seen)
      continue()
    endif()
    list(APPEND seen "${to}")
    string(REGEX REPLACE "[\r\n]" " " shown "${m}")
    check_pair("${rel}" "${to}" "${top_levels}" "${shown}" bad)
    string(FIND "${rel}" "lib/" rl)
    string(FIND "${to}" "lib/" tlib)
    if(rl EQUAL 0 AND tlib EQUAL 0)
      classify("${to}" "${lib_levels}" tol tou)
      if(tol LESS 0)
        string(APPEND bad "${f}: ${shown}  (${to}: folder of lib/ without a level)\n")
      else()
        check_pair("${rel}" "${to}" "${lib_levels}" "${shown}" bad)
      endif()
    endif()
  endforeach()
endforeach()

list(LENGTH files nfiles)
if(bad)
  message(NOTICE "${bad}")
  message(FATAL_ERROR "layering: forbidden includes (listed above)")
endif()
message(STATUS "layering: no forbidden includes (${nfiles} files)")
