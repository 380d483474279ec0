#!/bin/bash
# Every command printed in README.md and docs/*.md runs as printed from the repository root.
#
# A command is a line of a fenced code block that starts with `cambium`, `build/bin/cambium` or
# `$ cambium` (a trailing `\` joins the next line). The commands of one document run in order
# (a later one may read what an earlier one wrote) in a scratch directory that holds a link to
# every top-level entry of the repository, so paths read as from the root and outputs land in
# the scratch directory; `cambium` and `build/bin/cambium` are the tool under test. Each must
# exit 0 within 300 s (a command whose comment says `# exit N` must exit N). A failure names
# the document and line.
#
# Not run, and why:
#   - synopsis lines (placeholders such as MODEL.l or FILE, `[optional]` parts, `...`, or
#     `a | b` alternatives of options): they show a syntax, they are not commands;
#   - a command piping into a program that is not installed (an image viewer).
# Shortened, and why (the run stays the same command, only smaller; every option and file of
# the printed command is still used):
#   - `cambium grow` grows at most 3 years (`-y 3`, also when the printed command takes the
#     model's 10), and the L+C fruit tree `models/taylor-hell-fruit-tree.l` at most 3
#     (`-D YEARS=3`): a year of growth takes about a second and the years change no option;
#   - pictures (`.png`) without `--size` are drawn 200 pixels wide with one occlusion ray and
#     no supersampling: the default 800 x 800 picture costs seconds of ray casting per file;
#   - `cambium demo --segments N` draws at most 5000 segments (the benchmark's 100000 take 15 s).
# So the whole takes about a minute on one core.
set -u
BIN=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SRC=${CBM_SOURCE:?}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

mkdir -p "$T/bin"
ln -s "$BIN" "$T/bin/cambium"
export PATH="$T/bin:$PATH"

# FILE:LINE:COMMAND for every command of the fenced blocks of one document
extract() {
    awk '
        /^[ \t]*```/ { fence = !fence; joining = 0; next }
        !fence { next }
        joining {
            line = $0
            sub(/^[ \t]+/, " ", line)
            cmd = cmd line
            if (cmd ~ /\\$/) { sub(/\\$/, "", cmd); next }
            print FILENAME ":" start ":" cmd; joining = 0; next
        }
        {
            line = $0
            sub(/^[ \t]+/, "", line)
            sub(/^\$ /, "", line)
            if (line !~ /^(build\/bin\/)?cambium( |$)/) next
            start = FNR; cmd = line
            if (cmd ~ /\\$/) { sub(/\\$/, "", cmd); joining = 1; next }
            print FILENAME ":" start ":" cmd
        }' "$1"
}

# the reason a line is not run, or nothing
skip_reason() {
    local c=$1 p
    if [[ $c =~ \[|\.\.\.|…|\ \|\ - ]] ||
        grep -qE '(^| )[A-Z][A-Z0-9_]*(\.[a-z]+)?( |$)' <<<"$c"; then
        echo "a synopsis (placeholders, optional parts or alternatives)"
        return
    fi
    for p in $(grep -oE '\|[[:space:]]*[A-Za-z0-9_.-]+' <<<"$c" | tr -d '| '); do
        command -v "$p" >/dev/null || { echo "pipes into $p, which is not installed"; return; }
    done
}

# the command as run (see the header), and what was changed on stderr
shorten() {
    local c=$1 why=""
    c=$(sed -E 's/[[:space:]]+#[[:space:]].*$//' <<<"$c")
    if grep -qE '(^|/)cambium grow( |$)' <<<"$c" && ! grep -qE -- '--params|--help' <<<"$c"; then
        if grep -qE -- '(^| )(-y|-n|--years) [0-9]+' <<<"$c"; then
            local y
            y=$(grep -oE -- '(^| )(-y|-n|--years) [0-9]+' <<<"$c" | head -1 | grep -oE '[0-9]+$')
            if [ "$y" -gt 3 ]; then
                c=$(sed -E 's/(^| )(-y|-n|--years) [0-9]+/\1\2 3/' <<<"$c")
                why="$why 3 years;"
            fi
        else
            c=$(sed -E 's/cambium grow/cambium grow -y 3/' <<<"$c")
            why="$why 3 years;"
        fi
    fi
    if grep -qE 'taylor-hell-fruit-tree(-thesis)?\.l' <<<"$c"; then
        if grep -qE -- '-D YEARS=[0-9]+' <<<"$c"; then
            local y
            y=$(grep -oE -- '-D YEARS=[0-9]+' <<<"$c" | head -1 | grep -oE '[0-9]+$')
            [ "$y" -gt 3 ] && c=$(sed -E 's/-D YEARS=[0-9]+/-D YEARS=3/' <<<"$c") && why="$why 3 years;"
        else
            c=$(sed -E 's/(taylor-hell-fruit-tree(-thesis)?\.l)/\1 -D YEARS=3/' <<<"$c")
            why="$why 3 years;"
        fi
    fi
    # (cambium plot's pictures are cheap and take --size WxH: left as printed)
    if grep -qE -- '-o ([^ ]*\.png|png:)' <<<"$c" && ! grep -q -- '--size' <<<"$c" &&
        ! grep -qE '^(build/bin/)?cambium plot ' <<<"$c"; then
        c="$c --size 200 --ao 1 --supersample 1"
        why="$why 200-pixel pictures;"
    fi
    if grep -qE -- '--segments [0-9]{5,}' <<<"$c"; then
        c=$(sed -E 's/--segments [0-9]+/--segments 5000/' <<<"$c")
        why="$why 5000 segments;"
    fi
    [ -n "$why" ] && echo "${why% ;}" >&2
    printf '%s\n' "$c"
}

fails=0 ran=0 skipped=0
for doc in "$SRC/README.md" "$SRC"/docs/*.md; do
    rel=${doc#"$SRC"/}
    W="$T/work/${rel//\//_}"
    mkdir -p "$W/build/bin"
    ln -s "$BIN" "$W/build/bin/cambium"
    for e in "$SRC"/* "$SRC"/.[!.]*; do
        name=$(basename "$e")
        [ -e "$e" ] && [ "$name" != .git ] && [ "$name" != build ] && ln -s "$e" "$W/$name"
    done
    while IFS= read -r entry; do

        rest=${entry#*:}
        line=${rest%%:*}
        cmd=${rest#*:}
        where="$rel:$line"
        why=$(skip_reason "$cmd")
        if [ -n "$why" ]; then
            skipped=$((skipped + 1))
            echo "skip $where: $why"
            continue
        fi
        want=0
        [[ $cmd =~ \#\ exit\ ([0-9]+) ]] && want=${BASH_REMATCH[1]}
        run=$(shorten "$cmd" 2>"$T/why")
        [ -s "$T/why" ] && echo "shortened $where:$(cat "$T/why")"
        ran=$((ran + 1))
        (cd "$W" && timeout 300 bash -c "$run") >"$T/out" 2>"$T/err" </dev/null
        rc=$?
        if [ "$rc" -ne "$want" ]; then
            fails=$((fails + 1))
            echo "FAIL $where: exit status $rc (expected $want): $cmd"
            [ "$run" != "$(sed -E 's/[[:space:]]+#[[:space:]].*$//' <<<"$cmd")" ] &&
                echo "     run as: $run"
            sed 's/^/     | /' "$T/err" | head -5
        fi

    done < <(cd "$SRC" && extract "$rel")
done
echo "$ran commands run, $skipped synopsis lines skipped, $fails failed"
[ "$fails" -eq 0 ] || exit 1
