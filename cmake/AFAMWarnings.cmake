# Warnings on for our own targets; AFAM_WARNINGS_AS_ERRORS turns them into errors (CI sets it).
option(AFAM_WARNINGS_AS_ERRORS "Treat warnings in project targets as errors" OFF)
function(afam_enable_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow>
    $<$<AND:$<COMPILE_LANGUAGE:CXX>,$<BOOL:${AFAM_WARNINGS_AS_ERRORS}>>:-Werror>)
endfunction()
