# A project others build on: installs this build into a fresh prefix, builds
# examples/custom_goal against it with find_package(Spec2Fab), runs its
# experiment and checks the print it tuned against the mass written out by
# hand. Run by CTest (package.custom_goal_example):
#   cmake -DBUILD=<build dir> -DSOURCE=<source dir> -DWORK=<scratch dir> -P build_example.cmake
foreach(var BUILD SOURCE WORK)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "build_example.cmake: -D${var}=... is required")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK})

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "failed (${code}): ${ARGN}\n${out}")
  endif()
endfunction()

run(${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix)
run(${CMAKE_COMMAND} -S ${SOURCE}/examples/custom_goal -B ${WORK}/example -G Ninja
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${WORK}/prefix)
run(${CMAKE_COMMAND} --build ${WORK}/example)

# The new parts are listed beside the shipped ones.
execute_process(COMMAND ${WORK}/example/custom_spec2fab list translator OUTPUT_VARIABLE listed)
foreach(name target_mass albedo caustics_texture)
  if(NOT listed MATCHES "  ${name} ")
    message(FATAL_ERROR "custom_spec2fab list translator does not show ${name}:\n${listed}")
  endif()
endforeach()

run(${WORK}/example/custom_spec2fab run -q ${SOURCE}/examples/custom_goal/hollow_box.json --out ${WORK}/run)
file(READ ${WORK}/run/result.json result)
string(JSON achieved GET "${result}" mass achieved_g)
string(JSON cut GET "${result}" mass cut_z_mm)
# By hand: the 40 x 30 x 20 mm box, solid below the cut z = h, a 2 mm wall
# above it, so the empty core is 36 x 26 x (18 - h) mm; VeroWhitePlus is
# 1175 kg/m^3: m(h) = 1.175e-3 g/mm^3 x (24000 - 936 (18 - h)) mm^3.
# CMake's arithmetic is on integers: figures in millionths.
function(millionths text out)
  if(NOT text MATCHES "^([0-9]+)(\\.([0-9]+))?$")
    message(FATAL_ERROR "not a plain decimal: ${text}")
  endif()
  set(whole "${CMAKE_MATCH_1}")
  set(fraction "${CMAKE_MATCH_3}000000")
  string(SUBSTRING "${fraction}" 0 6 fraction)
  string(REGEX REPLACE "^0+([0-9])" "\\1" fraction "${fraction}")
  math(EXPR value "${whole} * 1000000 + ${fraction}")
  set(${out} ${value} PARENT_SCOPE)
endfunction()
millionths(${cut} h)
millionths(${achieved} m)
math(EXPR by_hand "(24000000000 - 936 * (18000000 - ${h})) * 1175 / 1000000")
math(EXPR miss "${m} - ${by_hand}")
math(EXPR target_miss "${by_hand} - 20000000")
message(STATUS "cut z = ${cut} mm: simulated ${achieved} g, by hand ${by_hand} ug, target 20 g")
# The simulator's midpoint rule within 0.5 % of the mass by hand, and the
# tuned cut within one step (0.1 mm: 0.11 g) of the target.
if(miss GREATER 100000 OR miss LESS -100000)
  message(FATAL_ERROR "simulated ${achieved} g, by hand ${by_hand} millionths of a gram")
endif()
if(target_miss GREATER 110000 OR target_miss LESS -110000)
  message(FATAL_ERROR "the cut at ${cut} mm misses the 20 g target: ${by_hand} millionths of a gram")
endif()
foreach(file tree.json preview/section_xz.png print/VeroWhitePlus.stl preview/render.png)
  if(NOT EXISTS ${WORK}/run/${file})
    message(FATAL_ERROR "the example's run wrote no ${file}")
  endif()
endforeach()
