# Third-party libraries, all from Debian packages (see cmake/debian-packages.txt, installed by
# `make deps`). Each is required: the build stops with the package to install if one is missing.
set(CBM_DEP_LIBS "")
set(CBM_DEP_INCLUDES "")
