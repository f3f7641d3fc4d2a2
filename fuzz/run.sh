#!/usr/bin/env bash
# Runs every fuzz target of the controller core for a while and summarises.
#
#   fuzz/run.sh [SECONDS_PER_TARGET]        (default 20)
#   TARGETS="protocol words" fuzz/run.sh 60 (a subset)
#
# Needs a nightly toolchain (`rustup toolchain install nightly`); installs
# cargo-fuzz (`cargo install cargo-fuzz --locked`) when it is missing.
# Each target starts from its committed seeds (fuzz/seeds/<target>/, copied
# into the working corpus fuzz/corpus/<target>/, which is not committed) and
# whatever the corpus already holds from earlier runs. Prints one line per
# target with the executions and the coverage reached; exits non-zero if any
# target found a crash or a broken invariant (the input is left in
# fuzz/artifacts/<target>/, the log in fuzz/target/run-logs/<target>.log).
set -u -o pipefail

SECONDS_PER_TARGET="${1:-20}"
case "$SECONDS_PER_TARGET" in
'' | *[!0-9]*)
    echo "usage: $0 [SECONDS_PER_TARGET]" >&2
    exit 2
    ;;
esac

FUZZ_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(dirname "$FUZZ_DIR")"
cd "$ROOT" || exit 2

ALL_TARGETS="request block protocol length gcode words contour sync g76"
TARGETS="${TARGETS:-$ALL_TARGETS}"

# Longest input per target: sessions of many lines for the protocol and the
# structured target, one line for G-code, one number for lengths.
max_len() {
    case "$1" in
    protocol) echo 4096 ;;
    words) echo 8192 ;;
    contour) echo 8192 ;;
    gcode) echo 256 ;;
    request | block) echo 256 ;;
    length) echo 64 ;;
    *) echo 4096 ;;
    esac
}

# The sanitizer per target. The request parser runs at volume without one:
# core-nostd forbids unsafe code, so AddressSanitizer finds nothing there
# that Rust's own checks do not, and costs it three quarters of its speed.
sanitizer() {
    case "$1" in
    request) echo none ;;
    *) echo address ;;
    esac
}

if ! cargo +nightly --version >/dev/null 2>&1; then
    echo "error: no nightly toolchain; install it with: rustup toolchain install nightly" >&2
    exit 2
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "cargo-fuzz not found; installing it (cargo install cargo-fuzz --locked)" >&2
    cargo install cargo-fuzz --locked || exit 2
fi

echo "building fuzz targets (cargo +nightly fuzz build) ..." >&2
if ! cargo +nightly fuzz build >&2; then
    echo "error: the fuzz targets do not build" >&2
    exit 2
fi

LOGS="$FUZZ_DIR/target/run-logs"
mkdir -p "$LOGS"
failed=""
summary=""
for t in $TARGETS; do
    corpus="$FUZZ_DIR/corpus/$t"
    mkdir -p "$corpus" "$FUZZ_DIR/artifacts/$t"
    # The parser alone starts from the block lines' seeds and dictionary.
    from="$t"
    if [ "$t" = block ]; then
        from=gcode
    fi
    if [ -d "$FUZZ_DIR/seeds/$from" ]; then
        # Seeds are named by content or purpose; never overwrite corpus files.
        cp -n "$FUZZ_DIR/seeds/$from/"* "$corpus/" 2>/dev/null || true
    fi
    dict=()
    if [ -f "$FUZZ_DIR/dict/$from.dict" ]; then
        dict=("-dict=$FUZZ_DIR/dict/$from.dict")
    fi
    log="$LOGS/$t.log"
    echo "fuzzing $t for ${SECONDS_PER_TARGET}s ..." >&2
    cargo +nightly fuzz run -s "$(sanitizer "$t")" "$t" "$corpus" -- \
        -max_total_time="$SECONDS_PER_TARGET" \
        -max_len="$(max_len "$t")" \
        -timeout=120 \
        -print_final_stats=1 \
        "${dict[@]}" >"$log" 2>&1
    status=$?

    execs="$(grep -a 'stat::number_of_executed_units:' "$log" | tail -n 1 | awk '{print $2}')"
    last="$(grep -a -E '^#[0-9]+' "$log" | grep -a 'cov:' | tail -n 1)"
    cov="$(sed -n 's/.*cov: \([0-9]*\).*/\1/p' <<<"$last")"
    ft="$(sed -n 's/.*ft: \([0-9]*\).*/\1/p' <<<"$last")"
    corp="$(sed -n 's/.*corp: \([0-9]*\).*/\1/p' <<<"$last")"
    if [ -z "$execs" ]; then
        # No final stats (a crash ends the run early): the last status line.
        execs="$(sed -n 's/^#\([0-9]*\).*/\1/p' <<<"$last")"
    fi
    if [ "$status" -eq 0 ]; then
        result="ok"
    else
        result="FAILED (exit $status)"
        failed="$failed $t"
    fi
    per_s="?"
    if [ -n "$execs" ] && [ "$SECONDS_PER_TARGET" -gt 0 ]; then
        per_s=$((execs / SECONDS_PER_TARGET))
    fi
    line="$(printf '%-9s executions=%-10s per_s=%-8s cov=%-6s ft=%-7s corpus=%-6s %s' \
        "$t" "${execs:-?}" "$per_s" "${cov:-?}" "${ft:-?}" "${corp:-?}" "$result")"
    summary="$summary$line"$'\n'
    echo "$line"
    if [ "$status" -ne 0 ]; then
        grep -a -m 1 -E "panicked at|ERROR: libFuzzer|ERROR: AddressSanitizer" -A 3 "$log" | sed 's/^/    /'
        grep -a -o -E "Test unit written to .*" "$log" | sed 's/^/    /'
        echo "    log: $log"
    fi
done

echo
echo "summary (${SECONDS_PER_TARGET}s per target):"
printf '%s' "$summary"
if [ -n "$failed" ]; then
    echo "failed:$failed" >&2
    exit 1
fi
