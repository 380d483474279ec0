#!/usr/bin/env bash
# The hostile-input corpus (issue 15): models, specs, flags and files that once hung, crashed or
# exhausted the machine. Each case gives the command, the exit status and a substring of the
# message it must print; every run is bounded by a generous kill timeout and, where the tool
# allows it (not under AddressSanitizer, which reserves terabytes of address space), a memory
# ulimit. A timeout or a signal is a failure; the times are not asserted otherwise.
set -uo pipefail
bin=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
src=${CBM_SOURCE:-$(cd "$(dirname "$0")/../.." && pwd)}
H=$src/tests/hostile
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
failed=0
KILL_AFTER=120 # seconds: far above what any case takes, only to turn a hang into a failure
MEM_KB=3000000 # 3 GB of address space

# the memory ulimit when the tool runs under it (an ASan build does not)
ulimit_ok=0
if (ulimit -v $MEM_KB && "$bin" --version) >/dev/null 2>&1; then
    ulimit_ok=1
fi

# case NAME STATUS MESSAGE ARGS...: runs `cambium ARGS...` and checks the exit status and that
# stderr+stdout contain MESSAGE (empty: no check).
case_() {
    local name=$1 want=$2 msg=$3
    shift 3
    (
        [ $ulimit_ok = 1 ] && ulimit -v $MEM_KB
        cd "$T" && exec timeout -s KILL $KILL_AFTER "$bin" "$@"
    ) >"$T/out" 2>&1 </dev/null
    local got=$?
    if [ $got -ne "$want" ]; then
        echo "FAIL $name: exit status $got, expected $want"
        sed 's/^/    /' "$T/out" | head -5
        failed=1
    elif [ -n "$msg" ] && ! grep -qF -- "$msg" "$T/out"; then
        echo "FAIL $name: no '$msg' in:"
        sed 's/^/    /' "$T/out" | head -5
        failed=1
    fi
}

# ---- generated inputs (too long to keep as files) ----
chain() { # chain N SEP TERM: TERM SEP TERM SEP ... (N terms)
    local n=$1 sep=$2 term=$3 out=$3
    for ((q = 1; q < n; q++)); do out+="$sep$term"; done
    printf '%s' "$out"
}
X5000=$(chain 5000 + x)
printf '#include <lpfgall.h>\nderivation length: 1;\nmodule A(float);\nAxiom: A(1);\nA(x) : { produce A(%s); }\n' \
    "$X5000" >"$T/lpfg-chain.l"
printf 'Lsystem: 1\nderivation length: 1\nAxiom: A(1)\nA(x) --> A(%s)\nendlsystem\n' "$X5000" >"$T/cpfg-chain.l"
printf 'Lsystem: 1\nderivation length: 1\nAxiom: A(1)\nA(a) --> A(%s0)\nendlsystem\n' \
    "$(chain 3000 '' 'a?1:')" >"$T/cpfg-ternary.l"
printf '#include <lpfgall.h>\nderivation length: 1;\nmodule A(float);\nAxiom: A(1);\nA(a) : { float b; b = %s0; produce A(b); }\n' \
    "$(chain 3000 '' 'a>0?1:')" >"$T/lpfg-ternary.l"
printf '#include <lpfgall.h>\nderivation length: 1;\nmodule A(float);\nAxiom: A(1);\nA(a) : { float b; %s0; produce A(b); }\n' \
    "$(chain 3000 '' 'b=')" >"$T/lpfg-assign.l"
printf '#include <lpfgall.h>\nderivation length: 1;\nmodule A(float);\nAxiom: A(1);\nA(a) : { float b; %s b = 0; produce A(b); }\n' \
    "$(chain 3000 '' 'if (a > 1) b = 1; else ')" >"$T/lpfg-elseif.l"
printf 'Lsystem: 1\nderivation length: 1\nAxiom: A(1)\nA(a) : 1 { %s b = 0; } --> A(b)\nendlsystem\n' \
    "$(chain 3000 '' 'if (a > 1) b = 1; else ')" >"$T/cpfg-elseif.l"
# right context across 10^5 nested branches: linear (was quadratic, 20 s)
printf 'Lsystem: 1\nderivation length: 1\nAxiom: %s%s\nA > B --> C\nendlsystem\n' \
    "$(chain 100000 '' 'A[')" "$(chain 100000 '' ']B')" >"$T/cpfg-deep-rc.l"
# the same in the L+C dialect, right context and (going Backward) new right context
printf '#include <lpfgall.h>\nderivation length: 1;\nmodule A(); module B(); module C();\nAxiom: %s%s;\nA() > B() : { produce C(); }\n' \
    "$(chain 100000 '' 'A()SB()')" "$(chain 100000 '' 'EB()B()')" >"$T/lpfg-deep-rc.l"
printf '#include <lpfgall.h>\nderivation length: 1;\nmodule A(); module B(); module C();\nAxiom: %s%s;\nStartEach: { Backward(); }\nA() >> B() : { produce C(); }\n' \
    "$(chain 100000 '' 'A()SB()')" "$(chain 100000 '' 'EB()B()')" >"$T/lpfg-deep-nrc.l"
: >"$T/empty.l"
printf 'Lsystem: 1\nderivation length: 1\nAxiom: A\0B\nendlsystem\n' >"$T/nul.l"
mkfifo "$T/fifo.l"
printf 'Lsystem: 1\n#include "fifo.l"\nendlsystem\n' >"$T/include-fifo.l"
# glTF binaries: a truncated header, and a sound header around a broken JSON chunk
printf 'glTF\002\000\000\000\040\000\000\000garbagegarbage!!' >"$T/bad-header.glb"
printf 'glTF\002\000\000\000\044\000\000\000\020\000\000\000JSON{"nodes":[1,    ' >"$T/bad-json.glb"

# ---- L+C dialect: execution budget and depth guards ----
case_ lpfg-fib 1 "lpfg-fib.l:4:" run "$H/lpfg-fib.l" --max-operations 1000000
case_ lpfg-fib-msg 1 "(--max-operations)" run "$H/lpfg-fib.l" --max-operations 1000000
case_ lpfg-recurse 1 "function calls nested too deeply (--max-call-depth)" run "$H/lpfg-recurse.l"
case_ lpfg-loop 1 "more loop iterations in one step than the limit" \
    run "$H/lpfg-loop.l" --max-loop-iterations 100000
case_ lpfg-decomp-doubling 1 "lpfg-decomp-doubling.l:7:1: error: decomposition: more productions applied" \
    run "$H/lpfg-decomp-doubling.l" --max-operations 100000
case_ lpfg-chain 1 "expression or statement nested too deeply (limit 200" run "$T/lpfg-chain.l"
case_ lpfg-ternary 1 "nested too deeply" run "$T/lpfg-ternary.l"
case_ lpfg-assign 1 "nested too deeply" run "$T/lpfg-assign.l"
case_ lpfg-elseif 1 "nested too deeply" run "$T/lpfg-elseif.l"
printf '#include <lpfgall.h>\nderivation length: 1;\nmodule A(float);\nAxiom: A(1);\nA(x) : { produce A(%s); }\n' \
    "$(chain 900 + x)" >"$T/lpfg-chain900.l"
case_ lpfg-chain-raised 0 "" run "$T/lpfg-chain900.l" --max-expr-depth 1000
case_ expr-depth-cap 2 "--max-expr-depth: 6000 is too large" run "$T/lpfg-chain.l" --max-expr-depth 6000
case_ lpfg-div0 1 "lpfg-div0.l:5:20: error: step 1: a parameter of A is not a finite number" \
    run "$H/lpfg-div0.l"
case_ lpfg-div0-allowed 0 "warning: a parameter of A is not a finite number" \
    run "$H/lpfg-div0.l" --allow-nonfinite
case_ lpfg-group 1 "lpfg-group-1e40.l:5:6: error: group 1e+40 is out of range" \
    run "$H/lpfg-group-1e40.l"
case_ lpfg-unterminated-comment 1 "lpfg-unterminated-comment.l:5:1: error: unterminated comment" \
    run "$H/lpfg-unterminated-comment.l"

# ---- cpfg dialect ----
case_ cpfg-chain 1 "cpfg-chain.l:4:" run "$T/cpfg-chain.l"
case_ cpfg-ternary 1 "nested too deeply" run "$T/cpfg-ternary.l"
case_ cpfg-elseif 1 "nested too deeply" run "$T/cpfg-elseif.l"
case_ cpfg-define-doubling 1 "cpfg-define-doubling.l:44:8: error: the expansion of macro 'A40'" \
    run "$H/cpfg-define-doubling.l"
case_ cpfg-zero-increment 1 "cpfg-zero-increment.l:5:48: error: step 1: while loops ran for more" \
    run "$H/cpfg-zero-increment.l" --max-loop-iterations 100000
case_ cpfg-decomp-doubling 1 "cpfg-decomp-doubling.l:7:1: error: more productions applied" \
    run "$H/cpfg-decomp-doubling.l" --max-operations 100000
case_ cpfg-div0 1 "cpfg-div0.l:4:12: error: step 1: a module parameter is not a finite number" \
    run "$H/cpfg-div0.l"
case_ cpfg-div0-str 1 "not a finite number" run "$H/cpfg-div0.l" -o "$T/div0.str"
[ -e "$T/div0.str" ] && { echo "FAIL cpfg-div0-str: output written"; failed=1; }
case_ cpfg-F1e39-obj 1 "beyond single precision" run "$H/cpfg-F1e39.l" -o "$T/big.obj"
case_ cpfg-F1e39-glb 1 "not a finite number" run "$H/cpfg-F1e39.l" --float32 -o "$T/big.glb"
[ -e "$T/big.obj" ] || [ -e "$T/big.glb" ] && { echo "FAIL cpfg-F1e39: output written"; failed=1; }
case_ cpfg-deep-rc 0 "400000 modules" run "$T/cpfg-deep-rc.l"
case_ lpfg-deep-rc 0 "400000 modules" run "$T/lpfg-deep-rc.l"
case_ lpfg-deep-nrc 0 "400000 modules" run "$T/lpfg-deep-nrc.l"
case_ cpfg-define-bad 1 "note: the line uses the command line's -D N=1+" run "$H/cpfg-define.l" -D "N=1+"
case_ cpfg-define-chain 1 "nested too deeply" run "$H/cpfg-define.l" -D "N=$X5000"

# ---- files ----
case_ include-passwd 1 "outside the model's folder" run "$H/cpfg-include-passwd.l"
case_ include-dotdot 1 "outside the model's folder" run "$H/cpfg-include-dotdot.l"
case_ fifo-model 1 "not a regular file" run "$T/fifo.l"
case_ fifo-include 1 "include-fifo.l:2:1: error: cannot read included file" run "$T/include-fifo.l"
case_ fifo-include-why 1 "fifo.l': not a regular file" \
    run "$T/include-fifo.l"
case_ empty 1 "empty.l:1:1: error: the model is empty" run "$T/empty.l"
case_ nul 1 "nul.l:3:9: error: a NUL byte" run "$T/nul.l"
case_ info-bad-header 1 "malformed glTF" info "$T/bad-header.glb"
case_ info-bad-json 1 "malformed glTF: its JSON chunk is not a well-formed JSON object" \
    info "$T/bad-json.glb"

# ---- mechanics workbench: the default memory limit ----
case_ bend-segments 1 "out of memory" bend "$H/bend-segments.spec"
case_ bend-segments-limit 1 "the limit of 64 MB (--max-memory)" bend "$H/bend-segments.spec" \
    --max-memory 64

# ---- output files ----
echo old >"$T/ro.str"
chmod 444 "$T/ro.str"
case_ read-only 1 "the file is read-only" run "$H/cpfg-div0.l" --allow-nonfinite -o "$T/ro.str"
grep -qx old "$T/ro.str" || { echo "FAIL read-only: replaced"; failed=1; }
ln -s "$T/nowhere/x.str" "$T/dangling.str"
case_ dangling 1 "dangling" run "$H/cpfg-div0.l" --allow-nonfinite -o "$T/dangling.str"
[ -L "$T/dangling.str" ] || { echo "FAIL dangling: the link was replaced"; failed=1; }
case_ missing-folder 1 "does not exist" run "$H/lpfg-loop.l" -o "$T/none/x.obj"
echo old >"$T/mode.str"
chmod 600 "$T/mode.str"
case_ keep-mode 0 "" run "$H/cpfg-div0.l" --allow-nonfinite -o "$T/mode.str"
[ "$(stat -c %a "$T/mode.str")" = 600 ] || { echo "FAIL keep-mode: mode changed"; failed=1; }

# ---- usage of the limit flags ----
case_ bad-limit 2 "--max-operations expects a non-negative integer" run "$H/cpfg-div0.l" --max-operations x
case_ zero-limit 2 "--max-call-depth must be at least 1" run "$H/cpfg-div0.l" --max-call-depth 0

[ $failed = 0 ] && echo ok
exit $failed
