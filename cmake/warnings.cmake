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
  # Sanitizer builds link Embree (and with it the C++ runtime) from the start, as the library
  # did before it loaded Embree with dlopen (src/core/dynlib.h; dlopen then finds it loaded).
  # Loaded later, it defeats two things of the sanitizers: ASan's __cxa_throw interceptor looks
  # its target up at the start (Embree throws and catches C++ exceptions inside), and
  # LeakSanitizer neither sees the blocks Embree keeps in its thread-local storage nor survives
  # its exit scan with Embree's worker threads alive (test_ober's light tests: "Tracer caught
  # signal 11"). The release build does not link it.
  add_link_options(-Wl,--push-state,--no-as-needed,-lembree3,-lstdc++,--pop-state)
endif()

# Reproducible floating point: no contraction into FMA, never -ffast-math.
add_compile_options(-ffp-contract=off)

function(cbm_set_warnings target)
  target_compile_options(${target} PRIVATE ${CBM_WARNINGS})
  if(CBM_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
