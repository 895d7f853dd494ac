# spec2fab_optional_module(OPTION LIBRARY ["KIND:NAME" ...])
#
# Declares an optional module beside its target: the SPEC2FAB_WITH_* option
# that builds it, the library it wraps and the parts it brings as a user
# names them ("optimizer:nlopt", "print writer:3mf"). Called whether or not
# the module is built, so that a build without it can say which option left a
# named part out. The top CMakeLists writes every declaration into
# generated/core/optional_modules.inc, the table core/build_options.cpp
# holds; core itself names no module and no part.
function(spec2fab_optional_module option library)
  set(parts "")
  foreach(part IN LISTS ARGN)
    string(FIND "${part}" ":" colon)
    if(colon LESS 1)
      message(FATAL_ERROR "spec2fab_optional_module(${option}): a part is KIND:NAME, not '${part}'")
    endif()
    string(SUBSTRING "${part}" 0 ${colon} kind)
    math(EXPR after "${colon} + 1")
    string(SUBSTRING "${part}" ${after} -1 name)
    string(APPEND parts "{\"${kind}\", \"${name}\"}, ")
  endforeach()
  if(${option})
    set(built true)
  else()
    set(built false)
  endif()
  set_property(GLOBAL APPEND_STRING PROPERTY SPEC2FAB_OPTIONAL_MODULE_ROWS
               "    {\"${option}\", \"${library}\", ${built}, {${parts}}},\n")
endfunction()
