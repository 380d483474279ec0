# Warnings of the house style. -Wconversion is left out on purpose: in numerical code full of
# size_t indices and double arithmetic it mostly flags intended conversions; -Wshadow,
# -Wstrict-prototypes, -Wmissing-prototypes, -Wvla and -Wcast-qual catch the real mistakes.
set(CBM_WARNINGS
    -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wvla
    -Wcast-qual -Wformat=2 -Wundef -Wimplicit-fallthrough -Wno-unused-parameter)

if(CBM_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=undefined
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
  # ASan intercepts __cxa_throw and looks the real one up when the process starts; Embree,
  # loaded later with dlopen (src/core/dynlib.h), throws (and catches) C++ exceptions, which
  # would reach an interceptor without its target. The C++ runtime linked from the start gives
  # it one (sanitizer builds only).
  add_link_options(-Wl,--push-state,--no-as-needed,-lstdc++,--pop-state)
endif()

# Reproducible floating point: no contraction into FMA, never -ffast-math.
add_compile_options(-ffp-contract=off)

function(cbm_set_warnings target)
  target_compile_options(${target} PRIVATE ${CBM_WARNINGS})
  if(CBM_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
