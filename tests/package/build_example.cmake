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

# Public headers only: none private (*_impl.h) is installed, and every
# header an installed one includes ("x/y.h") is installed too.
file(GLOB_RECURSE installed RELATIVE ${WORK}/prefix/include/spec2fab ${WORK}/prefix/include/spec2fab/*.h)
list(LENGTH installed installed_count)
if(installed_count LESS 100)
  message(FATAL_ERROR "only ${installed_count} headers installed")
endif()
foreach(header IN LISTS installed)
  if(header MATCHES "_impl\\.h$")
    message(FATAL_ERROR "a private header is installed: ${header}")
  endif()
  file(STRINGS ${WORK}/prefix/include/spec2fab/${header} includes REGEX "^#include \"[^\"]+\"")
  foreach(line IN LISTS includes)
    string(REGEX REPLACE "^#include \"([^\"]+)\".*" "\\1" included "${line}")
    get_filename_component(folder ${header} DIRECTORY)
    set(found FALSE)
    foreach(root framework simulators translators ${folder})
      if(EXISTS ${WORK}/prefix/include/spec2fab/${root}/${included})
        set(found TRUE)
      endif()
    endforeach()
    if(NOT found)
      message(FATAL_ERROR "${header} includes \"${included}\", which is not installed")
    endif()
  endforeach()
endforeach()

# The default library holds no TetGen (AGPLv3) code; its own archive does.
execute_process(COMMAND nm -C ${WORK}/prefix/lib/libspec2fab.a OUTPUT_VARIABLE symbols)
if(symbols MATCHES "tetgenio|tetgenmesh|tetgenbehavior")
  message(FATAL_ERROR "libspec2fab.a has TetGen symbols")
endif()
set(with_tetgen FALSE)
if(EXISTS ${WORK}/prefix/lib/libspec2fab_tetgen.a)  # a build with SPEC2FAB_WITH_TETGEN
  set(with_tetgen TRUE)
  execute_process(COMMAND nm -C ${WORK}/prefix/lib/libspec2fab_tetgen.a OUTPUT_VARIABLE symbols)
  if(NOT symbols MATCHES "tetgenio")
    message(FATAL_ERROR "libspec2fab_tetgen.a has no TetGen symbols: is the component empty?")
  endif()
endif()
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

if(NOT with_tetgen)
  return()
endif()
# Linked against the default package, the program has no TetGen: it does
# not load libtet, and the fem simulator says how to get a mesher.
execute_process(COMMAND ldd ${WORK}/example/custom_spec2fab OUTPUT_VARIABLE libraries)
if(libraries MATCHES "libtet")
  message(FATAL_ERROR "custom_spec2fab, built without the tetgen component, loads libtet:\n${libraries}")
endif()
execute_process(COMMAND ${WORK}/example/custom_spec2fab simulate -q fem ${SOURCE}/datasets/simulations/fem_cantilever.json
                        --out ${WORK}/fem --repeat 1
                RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT code EQUAL 2 OR NOT out MATCHES "find_package\\(Spec2Fab COMPONENTS tetgen\\)")
  message(FATAL_ERROR "without the tetgen component, simulate fem should refuse to mesh (exit 2) naming it; got ${code}:\n${out}")
endif()

# With the component, the same program meshes and solves.
run(${CMAKE_COMMAND} -S ${SOURCE}/examples/custom_goal -B ${WORK}/example_tetgen -G Ninja
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCUSTOM_GOAL_WITH_TETGEN=ON)
run(${CMAKE_COMMAND} --build ${WORK}/example_tetgen)
run(${WORK}/example_tetgen/custom_spec2fab simulate -q fem ${SOURCE}/datasets/simulations/fem_cantilever.json
    --out ${WORK}/fem_tetgen --repeat 1)
if(NOT EXISTS ${WORK}/fem_tetgen/displacements.csv)
  message(FATAL_ERROR "with the tetgen component, simulate fem wrote no displacements.csv")
endif()
