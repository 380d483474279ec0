#!/usr/bin/env bash
# `make install` into a temporary DESTDIR, then the README's linking recipe against the installed
# tree: the example examples/linking/bend_rod.c compiled with `pkg-config --cflags --libs
# cambium` (shared library) and with `pkg-config --static` (static library), both run and agree.
# Also: the shared library exports the public API and nothing else (every CBM_API function of
# include/cambium, no other symbol), and the man page is clean roff naming every option of the
# commands' --help.
set -euo pipefail
bin=$1
build=$(cd "$(dirname "$bin")/.." && pwd)
src=${CBM_SOURCE:?}
fail() { echo "FAIL: $*"; exit 1; }
[ -f "$build/cmake_install.cmake" ] || { echo "skip: no install script in $build"; exit 0; }
command -v pkg-config >/dev/null || { echo "skip: no pkg-config"; exit 0; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
stage=$tmp/stage
prefix=/opt/cambium-test
DESTDIR=$stage cmake --install "$build" --prefix "$prefix" >"$tmp/install.log"
root=$stage$prefix
for f in bin/cambium lib/libcambium.a lib/libcambium.so include/cambium/cambium.h \
         lib/pkgconfig/cambium.pc share/man/man1/cambium.1 \
         share/doc/cambium/examples/linking/bend_rod.c; do
    [ -e "$root/$f" ] || fail "not installed: $f"
done
# the headers installed are the public ones, all of them
diff <(cd "$src/include/cambium" && ls *.h) <(cd "$root/include/cambium" && ls) >/dev/null ||
    fail "installed headers differ from include/cambium"

# exported symbols: exactly the CBM_API functions of the public headers
nm -D --defined-only "$root/lib/libcambium.so" | awk '$2 ~ /^[TDBR]$/ {print $3}' | sort >"$tmp/exported"
grep -v '^cbm_' "$tmp/exported" | grep -v -e '^_init$' -e '^_fini$' >"$tmp/foreign" || true
[ ! -s "$tmp/foreign" ] || fail "exported beyond cbm_*: $(head -5 "$tmp/foreign" | tr '\n' ' ')"
grep -c '^cbm__' "$tmp/exported" >/dev/null && fail "internal cbm__ symbols exported"
cat "$src"/include/cambium/*.h | tr '\n' ' ' | grep -o 'CBM_API[^;{]*(' |
    grep -o 'cbm_[a-z0-9_]*[ ]*($' | tr -d ' (' | sort -u >"$tmp/declared"
[ "$(wc -l <"$tmp/declared")" -gt 100 ] || fail "could not read the declarations"
missing=$(comm -23 "$tmp/declared" "$tmp/exported")
[ -z "$missing" ] || fail "declared but not exported: $missing"

# the sanitizer build's library needs the sanitizer runtime in the program too
san=""
grep -q '^CBM_SANITIZE:BOOL=ON' "$build/CMakeCache.txt" && san="-fsanitize=address,undefined"
export PKG_CONFIG_PATH=$root/lib/pkgconfig PKG_CONFIG_SYSROOT_DIR=$stage
pkg-config --exists cambium || fail "pkg-config does not find cambium"
[ "$(pkg-config --modversion cambium)" = "$("$bin" --version | cut -d' ' -f2)" ] ||
    fail "pkg-config version $(pkg-config --modversion cambium)"
ex=$root/share/doc/cambium/examples/linking/bend_rod.c
# shellcheck disable=SC2046
cc -std=c17 -Wall -Wextra -Werror $san "$ex" -o "$tmp/bend_shared" $(pkg-config --cflags --libs cambium) -lm
LD_LIBRARY_PATH=$root/lib "$tmp/bend_shared" >"$tmp/shared.out" || fail "shared example: $(cat "$tmp/shared.out")"
# (ldd into a file: `ldd | grep -q` under pipefail fails when grep stops reading early)
LD_LIBRARY_PATH=$root/lib ldd "$tmp/bend_shared" >"$tmp/ldd.out"
grep -q "libcambium.so.0 => $root/lib/" "$tmp/ldd.out" ||
    fail "the shared example does not use the installed libcambium.so"
# static: the archive by path, the rest from `pkg-config --static`
# shellcheck disable=SC2046
cc -std=c17 -Wall -Wextra -Werror $san "$ex" -o "$tmp/bend_static" $(pkg-config --cflags cambium) \
    "$root/lib/libcambium.a" $(pkg-config --static --libs cambium | sed 's/-lcambium//')
"$tmp/bend_static" >"$tmp/static.out" || fail "static example: $(cat "$tmp/static.out")"
cmp "$tmp/shared.out" "$tmp/static.out" || fail "shared and static runs differ"
grep -q '^cambium [0-9.]*: tip deflection .* passes, stage newton$' "$tmp/shared.out" ||
    fail "example output: $(cat "$tmp/shared.out")"

# the man page: no roff warnings; every long option of every command's --help is in it
man1=$root/share/man/man1/cambium.1
if command -v groff >/dev/null; then
    groff -man -Tutf8 -ww -z "$man1" 2>"$tmp/groff.err"
    [ ! -s "$tmp/groff.err" ] || fail "roff warnings: $(head -3 "$tmp/groff.err")"
    groff -man -Tutf8 "$man1" 2>/dev/null | sed 's/.\x08//g' >"$tmp/man.txt"
    for c in run grow bend buckle info demo plot elastica compare sweep; do
        { "$bin" "$c" --help 2>&1 || true; } | { grep -o -- '--[a-z][a-z0-9-]*' || true; } | sort -u | while read -r o; do
            [ "$o" = --help ] && continue
            grep -q -- "$o" "$tmp/man.txt" || { echo "FAIL: cambium.1 lacks $c $o"; exit 1; }
        done
    done
fi
echo ok
