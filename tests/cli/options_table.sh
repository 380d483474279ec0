#!/usr/bin/env bash
# The option tables of the tool (tools/cambium/options.h): every option a command's --help lists
# is one its parser takes; values reach their targets (-DNAME=VALUE attached or not); the usage
# errors keep their wording and exit 2.
set -uo pipefail
bin=$1
fail() { echo "FAIL: $*"; exit 1; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

# each option of each --help is known to its command's parser
for c in run grow bend buckle info demo plot compare sweep; do
    "$bin" "$c" --help >"$T/help" || fail "$c --help exits $?"
    for o in $(grep -oE -- '(^|[ ,])--[a-z][a-z0-9-]*' "$T/help" | tr -d ' ,' | sort -u); do
        [ "$o" = --help ] && continue
        # then a value (a flag leaves it a word of its own) and an unknown option, so that the
        # parse ends in a usage error before any work
        "$bin" "$c" "$o" 1 --zz-end >/dev/null 2>"$T/err" </dev/null
        grep -qE -- "unknown option.*$o" "$T/err" && fail "$c --help lists $o, its parser does not take it"
    done
done

# values reach their targets
"$bin" grow -Dyears=2 --params | grep -qx "years = 2" || fail "grow -DNAME=VALUE"
"$bin" grow -D years=3 --params | grep -qx "years = 3" || fail "grow -D NAME=VALUE"
# a command that hands its line on by the model it names finds the model after options with
# values: run's -D and --seed before a built-in tree (run hands it to grow), grow's -y and
# --size before an Oberlaender tree (grow hands it to Oberlaender's grow)
"$bin" run --seed 3 -D years=2 fruit-tree --params | grep -qx "years = 2" ||
    fail "run with options before a tree model"
"$bin" grow --size 100x100 -y 4 ober-rauh --params >"$T/ober" || fail "grow OPTIONS ober-rauh"
grep -qx "family = oberlaender" "$T/ober" && grep -qx "years = 4" "$T/ober" ||
    fail "grow with options before an Oberlaender model"
"$bin" demo --segments 40 --sides 5 -o "$T/d.obj" || fail "demo with values"
[ -s "$T/d.obj" ] || fail "demo wrote nothing"

# usage errors: exit 2 and the message
expect() {
    local msg=$1
    shift
    "$bin" "$@" >/dev/null 2>"$T/err" </dev/null
    local rc=$?
    [ $rc -eq 2 ] || fail "'$*' exits $rc, not 2"
    grep -qF -- "$msg" "$T/err" || fail "'$*' says: $(head -1 "$T/err") (expected: $msg)"
}
expect "cambium run: -n expects a non-negative integer up to 10^8" run x.l -n 100000001
expect "cambium run: -D expects NAME=VALUE" run x.l -D
expect "cambium run: unknown option '--bogus'" run x.l --bogus
expect "cambium run: --max-call-depth must be at least 1" run x.l --max-call-depth 0
expect "cambium run: --max-expr-depth: 1001 is too large" run x.l --max-expr-depth 1001
expect "cambium run: bad value '3' for --size" run x.l --size 3
expect "cambium run: --view needs a value" run x.l --view
expect "cambium grow: -y must be 0..1000" grow -y 1001
expect "cambium grow: unknown option or missing value: --years" grow --years
expect "cambium grow: unknown option --bogus" grow --bogus x
expect "cambium grow: more than one model: 'a' and 'b'" grow a b
expect "cambium grow: --seeds expects A-B with 0 <= A <= B, got '5-3'" grow --seeds 5-3
expect "cambium bend: -o needs a file name" bend a -o
expect "cambium bend: x.txt: unsupported output format '.txt' (use .csv or .json; .svg or .png with --continue)" bend a -o x.txt
expect "cambium buckle: --E is required (see --help)" buckle
expect "cambium buckle: --E: 'x' is not a number" buckle --E x
expect "cambium buckle: unknown option '--wobble' (see --help)" buckle --wobble
expect "cambium info: expected one FILE, got 'a' and 'b'" info a b
expect "cambium demo: --sides must be 3..64" demo --sides 2
expect "cambium plot: --panel comes after -y" plot a --panel 1
expect "cambium plot: --size: '10' is not WxH" plot a -y 1 --size 10
echo ok
