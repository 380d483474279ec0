# Sourced by the comparison scripts of tools/ (peers-compare.sh, same-outputs.sh,
# instr-compare.sh): the peer's command of an oracle model (the first cpfg or lpfg line of its
# ref/commands.txt) read into the model and side files that cambium runs too.
#
# oracle_command DIR: prints the command of oracle model DIR without its comment, nothing when it
# has none.
# oracle_files WORD...: the command's words (the peer first) into the array `files`: the model
# and side files in their order, without the options and the outputs they name.
# shellcheck shell=bash

oracle_command() {
    grep -m1 -E '^(cpfg|lpfg) ' "$1/ref/commands.txt" 2>/dev/null | sed 's/ *#.*//'
}

oracle_files() {
    local words=("$@") k
    files=()
    for ((k = 1; k < ${#words[@]}; k++)); do
        case ${words[k]} in
        -g | -b | -homo) ;;
        -str | -strb | -out | -o | -vv | -ray | -obj) k=$((k + 1)) ;;
        -m | -M) files+=("${words[k + 1]}"); k=$((k + 1)) ;;
        -*) ;;
        *) files+=("${words[k]}") ;;
        esac
    done
}
