# Warnings per target: -Wall -Wextra -Wpedantic everywhere, -Werror when TAXOPT_WERROR (CI).
function(taxopt_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                           -Wno-sign-conversion)
  if(TAXOPT_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
