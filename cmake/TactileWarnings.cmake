# Warning flags for every target of the project (not for generated Protobuf code).
function(tactile_set_warnings target)
  target_compile_options(${target} INTERFACE
    -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual
    -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough
    # GCC 12 reports std::string concatenation at -O3 as overlapping memcpy (GCC bug 105329).
    $<$<CXX_COMPILER_ID:GNU>:-Wno-restrict>)
  if(TACTILE_WERROR)
    target_compile_options(${target} INTERFACE -Werror)
  endif()
endfunction()
