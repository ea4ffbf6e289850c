# Warnings per target: -Wall -Wextra -Wpedantic everywhere, -Werror when TAXOPT_WERROR (CI).
function(taxopt_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                           -Wno-sign-conversion)
  # GCC's maybe-uninitialized is off under the sanitizers: with their instrumentation at -O1 it
  # warns inside libstdc++'s <regex> and <functional> (GCC's manual: sanitizers make that
  # warning unreliable); the release build keeps it.
  if(TAXOPT_SANITIZE)
    target_compile_options(${target} PRIVATE -Wno-maybe-uninitialized)
  endif()
  if(TAXOPT_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
