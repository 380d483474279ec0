#!/usr/bin/env bash
# The layer check of `make check` (.ci/check-layers.sh) on a copy of the tree with includes
# planted in it: it passes on the tree as it is, and rejects an include of another area's
# `*_internal.h` (however the path is spelled), an include of another area's header that
# includes its own area's internals (a header planted in src/lsys that includes
# lsys_internal.h), and an include of src/ from the tool; it accepts an area's own internals and
# another area's package header.
set -euo pipefail
src=${CBM_SOURCE:?}
fail() { echo "FAIL: $*"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/.ci"
cp "$src/.ci/check-layers.sh" "$tmp/.ci/"
cp -r "$src/src" "$src/tools" "$src/include" "$tmp/"
check() { bash "$tmp/.ci/check-layers.sh" >"$tmp/out" 2>&1; }
check || fail "the tree as it is: $(cat "$tmp/out")"
# plant one include at the end of a file, expect the check's verdict, take it out again
plant() {
    local file=$1 line=$2 verdict=$3
    cp "$tmp/$file" "$tmp/saved"
    echo "$line" >>"$tmp/$file"
    if check; then
        [ "$verdict" = accept ] || fail "$file: '$line' accepted"
    else
        [ "$verdict" = reject ] || fail "$file: '$line' rejected: $(cat "$tmp/out")"
        grep -q "^$file:" "$tmp/out" || fail "the message does not name $file: $(cat "$tmp/out")"
    fi
    mv "$tmp/saved" "$tmp/$file"
}
plant src/tree/tree_spring.c '#include "mech/mech_internal.h"' reject
plant src/tree/tree_spring.c '#include "../io/../mech/./growth_internal.h"' reject
plant src/lsys_model/model.c '#include "lsys/lsys_internal.h"' reject
plant src/lsys_model/model.c '#include "lsys/mechlang_internal.h"' reject
plant src/io/gltf.c '#include "../turtle/view_internal.h"' reject
echo '#include "lsys_internal.h"' >"$tmp/src/lsys/planted.h"
plant src/lsys_model/model.c '#include "lsys/planted.h"' reject
rm "$tmp/src/lsys/planted.h"
plant tools/cambium/cmd_info.c '#include "../../src/core/core.h"' reject
plant src/mech/bend.c '#include "mech/growth_internal.h"' accept
plant src/tree/tree_spring.c '#include "mech/mech.h"' accept
plant src/lsys_model/model.c '#include "lsys/lsys.h"' accept
echo ok
