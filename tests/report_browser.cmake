# The HTML report in a real browser: `tb compare SCENE` writes a report (plots as SVG, images as
# PNG), headless Chromium loads it inside a same-folder page that counts the report's <img>
# elements and those that failed to load, and its console log is read for errors; a screenshot
# of the report is saved. Negative control: a copy of the report with one image deleted and a
# script error appended must show both faults (one broken image, one console error).
# Run by the CTest report_browser:
#   cmake -DTB=<tb> -DCHROMIUM=<chromium> -DSOURCE_DIR=<source tree> -DWORK=<scratch> -P tests/report_browser.cmake
cmake_minimum_required(VERSION 3.20)
foreach(v TB CHROMIUM SOURCE_DIR WORK)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "report_browser.cmake: pass -D${v}=...")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
set(scene "${SOURCE_DIR}/scenes/cornell-box.json")

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "report_browser: ${what}: exit ${rc}\n${out}\n${err}")
  endif()
endfunction()

# A small report: a 16x16 bdpt reference, then pt and bdpt at equal time (three checkpoints).
run("reference" "${TB}" render "${scene}" --integrator bdpt --spp 64 --passes 8 --resolution 16x16 --no-progress
    -o "${WORK}/reference.exr")
run("tb compare" "${TB}" compare "${scene}" --integrators pt,bdpt --time 0.3 --resolution 16x16
    --reference "${WORK}/reference.exr" --no-progress -o "${WORK}/report")

# The broken copy (negative control).
file(COPY "${WORK}/report/" DESTINATION "${WORK}/broken")
file(GLOB pngs "${WORK}/broken/images/*.png")
list(LENGTH pngs n_png)
if(n_png EQUAL 0)
  message(FATAL_ERROR "report_browser: the report has no PNG images")
endif()
list(GET pngs 0 victim)
file(REMOVE "${victim}")
file(READ "${WORK}/broken/index.html" html)
string(REPLACE "</body>" "<script>report_browser_no_such_function();</script></body>" html "${html}")
file(WRITE "${WORK}/broken/index.html" "${html}")

# load(<folder> <out prefix>): sets <prefix>_images, <prefix>_broken, <prefix>_errors.
function(load folder prefix)
  file(WRITE "${WORK}/probe-${folder}.html" "<!doctype html><html><body>
<iframe id=\"f\" src=\"${folder}/index.html\" width=\"1200\" height=\"900\"></iframe><pre id=\"result\">pending</pre>
<script>
document.getElementById('f').addEventListener('load', () => setTimeout(() => {
  const imgs = Array.from(document.getElementById('f').contentDocument.images);
  const bad = imgs.filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.getAttribute('src'));
  document.getElementById('result').textContent = 'report-images=' + imgs.length + ';broken=' + bad.length + ';' + bad.join(',');
}, 300));
</script></body></html>
")
  execute_process(COMMAND "${CHROMIUM}" --headless --no-sandbox --disable-gpu --allow-file-access-from-files
                          --virtual-time-budget=5000 --enable-logging=stderr --v=0
                          --dump-dom "file://${WORK}/probe-${folder}.html"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE dom ERROR_VARIABLE log TIMEOUT 120)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "report_browser: chromium exit ${rc}\n${log}")
  endif()
  if(NOT dom MATCHES "report-images=([0-9]+);broken=([0-9]+);([^<]*)")
    message(FATAL_ERROR "report_browser: the probe page did not finish loading ${folder}\n${log}")
  endif()
  set(${prefix}_images ${CMAKE_MATCH_1} PARENT_SCOPE)
  set(${prefix}_broken ${CMAKE_MATCH_2} PARENT_SCOPE)
  set(${prefix}_broken_list "${CMAKE_MATCH_3}" PARENT_SCOPE)
  # Console errors of the report page (uncaught exceptions, failed resources), not of the probe.
  string(REGEX MATCHALL "CONSOLE[^\n]*source: file://${WORK}/${folder}/[^\n]*" errs "${log}")
  list(LENGTH errs n_err)
  set(${prefix}_errors ${n_err} PARENT_SCOPE)
  set(${prefix}_error_list "${errs}" PARENT_SCOPE)
endfunction()

load(report good)
load(broken bad)
message("report: ${good_images} images, ${good_broken} broken, ${good_errors} console errors")
message("negative control: ${bad_images} images, ${bad_broken} broken (${bad_broken_list}), ${bad_errors} console errors")
set(failures "")
if(good_images LESS 4)
  string(APPEND failures "the report shows ${good_images} images, expected the 2 plots and at least 2 renders\n")
endif()
if(NOT good_broken EQUAL 0)
  string(APPEND failures "broken images in the report: ${good_broken_list}\n")
endif()
if(NOT good_errors EQUAL 0)
  string(APPEND failures "console errors in the report: ${good_error_list}\n")
endif()
if(NOT bad_broken EQUAL 1 OR bad_errors LESS 1)
  string(APPEND failures "negative control not caught: ${bad_broken} broken images, ${bad_errors} console errors\n")
endif()
if(failures)
  message(FATAL_ERROR "report_browser:\n${failures}")
endif()

execute_process(COMMAND "${CHROMIUM}" --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1200,1600
                        --virtual-time-budget=5000 "--screenshot=${WORK}/report.png" "file://${WORK}/report/index.html"
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET TIMEOUT 120)
if(NOT rc EQUAL 0 OR NOT EXISTS "${WORK}/report.png")
  message(FATAL_ERROR "report_browser: no screenshot (chromium exit ${rc})")
endif()
message("screenshot: ${WORK}/report.png")
