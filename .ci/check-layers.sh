#!/usr/bin/env bash
# The layering rule of the library (docs/design.md, "Layers"): each area of src/ (a folder:
# core, mech, tree, ...) keeps its `*_internal.h` headers to itself and offers the other areas
# its package headers (the other headers of the folder, e.g. src/mech/mech.h). This check lists
# every `#include "..."` of src/ that reaches another area's `*_internal.h`, and every include of
# tools/ (the command-line tool, public API only) that reaches into src/. Run by `make check`.
#
# Known exceptions, each with the reason it stands (remove the line when it is fixed):
#   src/lsys_model/model.c -> src/lsys/lsys_internal.h: the model reads the engine's string, its
#     production counts and the L+C mechanics fields; the accessors belong in an lsys package
#     header, written with the restructuring of src/lang and src/lsys (issue 10, item 1).
set -euo pipefail
cd "$(dirname "$0")/.."
allowed=(
    "src/lsys_model/model.c src/lsys/lsys_internal.h"
)
bad=0
# the path an include names, as the compiler finds it (-I include -I src, then the file's folder)
resolve() {
    local from=$1 inc=$2 dir
    dir=$(dirname "$from")
    if [ -e "$dir/$inc" ]; then
        realpath -m --relative-to=. "$dir/$inc"
    elif [ -e "src/$inc" ]; then
        realpath -m --relative-to=. "src/$inc"
    elif [ -e "include/$inc" ]; then
        realpath -m --relative-to=. "include/$inc"
    else
        echo "$inc"
    fi
}
while IFS=: read -r file line text; do
    inc=$(sed -E 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"([^"]+)".*/\1/' <<<"$text")
    target=$(resolve "$file" "$inc")
    case $file in
    src/*)
        [[ $target == src/*_internal.h ]] || continue
        from_area=$(cut -d/ -f2 <<<"$file")
        to_area=$(cut -d/ -f2 <<<"$target")
        [ "$from_area" = "$to_area" ] && continue
        for a in "${allowed[@]}"; do
            [ "$a" = "$file $target" ] && continue 2
        done
        echo "$file:$line: includes $target, internal to src/$to_area (use its package header)"
        bad=1
        ;;
    tools/*)
        [[ $target == src/* ]] || continue
        echo "$file:$line: the tool includes $target (tools use the public API, include/cambium)"
        bad=1
        ;;
    esac
done < <(grep -rnE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"[^"]*_internal\.h"' src \
             --include='*.c' --include='*.h'
         grep -rnE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' tools --include='*.c' \
             --include='*.h' | grep -vE '#[[:space:]]*include[[:space:]]*"(cambium/|[^/"]+")' || true)
[ $bad -eq 0 ] || { echo "check-layers: includes above cross the layers"; exit 1; }
echo "check-layers: clean"
