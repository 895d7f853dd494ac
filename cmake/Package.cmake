# `cmake --install` and find_package(Spec2Fab): the command, one static
# library of every module but TetGen's (libspec2fab.a: spec2fab_modules, MIT),
# TetGen's module on its own (libspec2fab_tetgen.a, AGPLv3: the opt-in
# component "tetgen"), the command's
# objects (libspec2fab_cli.a), the headers under include/spec2fab/, and a
# config file (cmake/Spec2FabConfig.cmake.in) that finds the dependencies
# again and links the library whole. examples/custom_goal builds against it,
# and tests/package builds and runs that example.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# What the modules link outside themselves — imported targets, system
# libraries — walked from their link properties, so that the list is never
# written twice.
function(spec2fab_external_libraries out)
  set(queue ${ARGN})
  set(seen)
  set(external)
  while(queue)
    list(POP_FRONT queue target)
    if(target IN_LIST seen)
      continue()
    endif()
    list(APPEND seen ${target})
    get_target_property(private ${target} LINK_LIBRARIES)
    get_target_property(public ${target} INTERFACE_LINK_LIBRARIES)
    foreach(item IN LISTS private public)
      if(NOT item OR item MATCHES "NOTFOUND$")
        continue()
      endif()
      if(item MATCHES "^\\\$<LINK_ONLY:(.*)>$")
        set(item ${CMAKE_MATCH_1})
      endif()
      if(item MATCHES "^spec2fab_")
        list(APPEND queue ${item})
      elseif(NOT item IN_LIST external)
        list(APPEND external ${item})
      endif()
    endforeach()
  endwhile()
  set(${out} ${external} PARENT_SCOPE)
endfunction()
spec2fab_external_libraries(SPEC2FAB_EXTERNAL_LIBRARIES ${SPEC2FAB_MODULES})

install(TARGETS spec2fab RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS spec2fab-read-mesh RUNTIME DESTINATION ${CMAKE_INSTALL_LIBEXECDIR})  # load_mesh looks there
install(FILES $<TARGET_FILE:spec2fab_modules> DESTINATION ${CMAKE_INSTALL_LIBDIR} RENAME libspec2fab.a)
if(TARGET spec2fab_tetgen_archive)
  install(FILES $<TARGET_FILE:spec2fab_tetgen_archive> DESTINATION ${CMAKE_INSTALL_LIBDIR} RENAME libspec2fab_tetgen.a)
endif()
install(FILES $<TARGET_FILE:spec2fab_cli_archive> DESTINATION ${CMAKE_INSTALL_LIBDIR} RENAME libspec2fab_cli.a)
# Public headers only: a header named *_impl.h is private to its folder's
# sources (tests/package checks that no installed header includes one).
foreach(root framework simulators translators)
  install(DIRECTORY ${root}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/spec2fab/${root}
          FILES_MATCHING PATTERN "*.h" PATTERN "*_impl.h" EXCLUDE)
endforeach()
install(FILES ${PROJECT_BINARY_DIR}/generated/core/build_options.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/spec2fab/framework/core)
set(package_dir ${CMAKE_INSTALL_LIBDIR}/cmake/Spec2Fab)
file(RELATIVE_PATH SPEC2FAB_PREFIX_FROM_PACKAGE "/${package_dir}" "/")  # "../../.." for lib/cmake/Spec2Fab
configure_file(cmake/Spec2FabConfig.cmake.in Spec2FabConfig.cmake @ONLY)
write_basic_package_version_file(Spec2FabConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/Spec2FabConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/Spec2FabConfigVersion.cmake
        DESTINATION ${package_dir})
install(FILES cmake/Dependencies.cmake DESTINATION ${package_dir} RENAME Spec2FabDependencies.cmake)
