# Third-party libraries, all from Debian packages (see cmake/debian-packages.txt, installed by
# `make deps`). Each is required: the build stops with the package to install if one is missing.
set(CBM_DEP_LIBS "")
set(CBM_DEP_INCLUDES "")
find_package(embree 3 REQUIRED) # libembree-dev: ray casting of the PNG renderer (and light)
find_package(PNG REQUIRED) # libpng-dev: PNG encoding and decoding
find_package(Threads REQUIRED) # render threads
find_package(PkgConfig REQUIRED) # pkg-config: finds cairo
pkg_check_modules(CAIRO REQUIRED IMPORTED_TARGET cairo) # libcairo2-dev: plots and picture text
list(APPEND CBM_DEP_LIBS embree PNG::PNG Threads::Threads PkgConfig::CAIRO)
