#!/usr/bin/env bash
# The layering rule of the library (docs/design.md, "Layers"): each area of src/ (a folder:
# core, mech, tree, ...) keeps its `*_internal.h` headers to itself and offers the other areas
# its package headers (the other headers of the folder, e.g. src/mech/mech.h). A header that
# includes its area's internals (itself or through another header) is internal as well, whatever
# its name, since including it reaches them. This check lists every `#include "..."` of src/ that
# reaches another area's internal header, and every include of tools/ (the command-line tool,
# public API only) that reaches into src/. Run by `make check`.
#
# Known exceptions, each with the reason it stands (remove the line when it is fixed): none.
set -euo pipefail
cd "$(dirname "$0")/.."
allowed=()
bad=0
# a path without its "." and ".." parts (bash alone: the check runs over every include)
normalize() {
    local IFS=/ part out=()
    for part in $1; do
        case $part in
        '' | .) ;;
        ..) [ ${#out[@]} -gt 0 ] && unset 'out[${#out[@]}-1]' ;;
        *) out+=("$part") ;;
        esac
    done
    echo "${out[*]}"
}
# the path an include names, as the compiler finds it (-I include -I src, then the file's folder)
resolve() {
    local from=$1 inc=$2 dir
    dir=${from%/*}
    if [ -e "$dir/$inc" ]; then
        normalize "$dir/$inc"
    elif [ -e "src/$inc" ]; then
        normalize "src/$inc"
    elif [ -e "include/$inc" ]; then
        normalize "include/$inc"
    else
        echo "$inc"
    fi
}
# the includes of a file, resolved
includes_of() {
    grep -hE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$1" |
        sed -E 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"([^"]+)".*/\1/' |
        while read -r inc; do resolve "$1" "$inc"; done
}
# internal headers: *_internal.h, then (until nothing is added) every header of src/ that
# includes an internal header of its own area
declare -A internal=()
for h in $(find src -name '*_internal.h' | sort); do internal[$h]=1; done
grown=1
while [ $grown -eq 1 ]; do
    grown=0
    for h in $(find src -name '*.h' | sort); do
        [ -n "${internal[$h]:-}" ] && continue
        area=${h#src/}
        area=${area%%/*}
        for t in $(includes_of "$h"); do
            if [ -n "${internal[$t]:-}" ] && [[ $t == src/$area/* ]]; then
                internal[$h]=1
                grown=1
                break
            fi
        done
    done
done
while IFS=: read -r file line text; do
    [[ $text =~ \"([^\"]+)\" ]] || continue
    inc=${BASH_REMATCH[1]}
    target=$(resolve "$file" "$inc")
    case $file in
    src/*)
        [ -n "${internal[$target]:-}" ] || continue
        from_area=${file#src/}
        from_area=${from_area%%/*}
        to_area=${target#src/}
        to_area=${to_area%%/*}
        [ "$from_area" = "$to_area" ] && continue
        for a in "${allowed[@]+"${allowed[@]}"}"; do
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
done < <(grep -rnE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' src \
             --include='*.c' --include='*.h'
         grep -rnE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' tools --include='*.c' \
             --include='*.h' | grep -vE '#[[:space:]]*include[[:space:]]*"(cambium/|[^/"]+")' || true)
[ $bad -eq 0 ] || { echo "check-layers: includes above cross the layers"; exit 1; }
echo "check-layers: clean"
