# Third-party libraries, all from Debian packages (see cmake/debian-packages.txt, installed by
# `make deps`). Each is required: the build stops with the package to install if one is missing.
# Embree and cairo are compiled against (their headers give the types and the signatures) but not
# linked: the library loads them with dlopen when it first casts a ray or draws text
# (src/core/dynlib.h), so that the runs that do neither do not map them and the twenty-odd
# libraries they bring at every start. CBM_DEP_LIBS are linked, CBM_DEP_INCLUDES only compiled
# against.
set(CBM_DEP_LIBS "")
set(CBM_DEP_INCLUDES "")
find_package(embree 3 REQUIRED) # libembree-dev: ray casting of the PNG renderer (and light)
find_package(PNG REQUIRED) # libpng-dev: PNG encoding and decoding
find_package(Threads REQUIRED) # render threads
find_package(PkgConfig REQUIRED) # pkg-config: finds cairo
pkg_check_modules(CAIRO REQUIRED IMPORTED_TARGET cairo) # libcairo2-dev: plots and picture text
list(APPEND CBM_DEP_LIBS PNG::PNG Threads::Threads)
list(APPEND CBM_DEP_INCLUDES $<TARGET_PROPERTY:embree,INTERFACE_INCLUDE_DIRECTORIES>
            $<TARGET_PROPERTY:PkgConfig::CAIRO,INTERFACE_INCLUDE_DIRECTORIES>)
