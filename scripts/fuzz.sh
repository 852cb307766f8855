#!/usr/bin/env bash
# cargo-fuzz (libFuzzer) runs of the targets in fuzz/ (see "Fuzzing" in
# docs/book/src/reliability.md for what each target checks).
#
#   bash scripts/fuzz.sh smoke          # every target a few seconds; CI
#   bash scripts/fuzz.sh long           # every target to 10^7 runs (or a time cap)
#   bash scripts/fuzz.sh long mailbox   # only some targets
#   bash scripts/fuzz.sh regressions    # replay fuzz/regressions/<target>/*
#
# Each target runs on fuzz/corpus/<target> (ignored by git: what the fuzzer
# finds), fuzz/seeds/<target> (committed seeds, see fuzz/examples/seed.rs)
# and fuzz/regressions/<target> (committed inputs that once crashed, so
# smoke and long replay them too):
#
#   cargo +nightly fuzz run -s none T fuzz/corpus/T fuzz/seeds/T fuzz/regressions/T -- ...
#
# smoke: -max_total_time=$FUZZ_SMOKE_SECONDS (8) per target; installs
#   cargo-fuzz and the nightly toolchain when missing; fails on any crash,
#   panic, timeout or leak (libFuzzer's exit status), printing the panic
#   and the input (base64, up to 16 KiB; saved under fuzz/artifacts/<target>/).
# long: -runs=$FUZZ_LONG_RUNS (10 000 000) capped at -max_total_time=
#   $FUZZ_LONG_SECONDS (900) per target, one target at a time; executions,
#   executions/s, coverage and corpus size per target go to
#   $FUZZ_LOG_DIR/long.log (default fuzz/logs), libFuzzer's output to
#   $FUZZ_LOG_DIR/<target>.log. Run it at low priority: nice -n 19 bash ...
# regressions: runs every saved input of fuzz/regressions/<target>/ once.
#
# Sanitizer: none by default ($FUZZ_SANITIZER to change): the crates forbid
# unsafe code, so AddressSanitizer would find nothing the panics do not,
# at half the speed. cargo-fuzz builds with debug assertions, so integer
# overflow panics too. The build goes to fuzz/target.
set -euo pipefail
cd "$(dirname "$0")/.."

mode="${1:-smoke}"
shift || true
all_targets=(line_frames mailbox sii esi efw hcs_telegram twin pam_invariants)
if [ $# -gt 0 ]; then targets=("$@"); else targets=("${all_targets[@]}"); fi

sanitizer="${FUZZ_SANITIZER:-none}"
log_dir="${FUZZ_LOG_DIR:-fuzz/logs}"

# Largest input per target: several frames, a bootstrap mailbox, a 4 KiB
# SII image as Intel HEX, an ESI of a small device, an HCS telegram (at
# most 28 bytes) in a process-data buffer, up to 128 master actions.
max_len() {
    case "$1" in
        line_frames) echo 16384 ;;
        mailbox) echo 8192 ;;
        sii) echo 16384 ;;
        esi) echo 65536 ;;
        efw) echo 8192 ;;
        hcs_telegram) echo 128 ;;
        twin) echo 65536 ;;
        pam_invariants) echo 1024 ;;
        *) echo 4096 ;;
    esac
}

ensure_tools() {
    if ! command -v rustup >/dev/null 2>&1; then
        echo "fuzz: rustup is needed for the nightly toolchain" >&2
        exit 1
    fi
    if ! rustup run nightly rustc --version >/dev/null 2>&1; then
        rustup toolchain install nightly --profile minimal
    fi
    if ! cargo fuzz --version >/dev/null 2>&1; then
        cargo install cargo-fuzz --locked
    fi
}

build() {
    cargo +nightly fuzz build -s "$sanitizer" "$@"
}

run_target() {
    local t="$1"
    shift
    mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
    # The saved crash inputs are read first with the seeds, so every run
    # replays them; new finds go to the first directory only.
    local dirs=("fuzz/corpus/$t" "fuzz/seeds/$t")
    if [ -d "fuzz/regressions/$t" ]; then dirs+=("fuzz/regressions/$t"); fi
    cargo +nightly fuzz run -s "$sanitizer" "$t" "${dirs[@]}" -- \
        -max_len="$(max_len "$t")" -timeout=30 -print_final_stats=1 "$@"
}

# The figures of a libFuzzer log: runs, exec/s, coverage, corpus.
figures() {
    local f="$1"
    local runs rate cov corp
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$f" | tail -1 | grep -o '[0-9]*$' || true)
    rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$f" | tail -1 | grep -o '[0-9]*$' || true)
    cov=$(grep -o 'cov: [0-9]*' "$f" | tail -1 | grep -o '[0-9]*$' || true)
    corp=$(grep -o 'corp: [0-9]*/[0-9a-zA-Z]*' "$f" | tail -1 | cut -d' ' -f2 || true)
    echo "runs=${runs:-?} exec/s=${rate:-?} cov=${cov:-?} corpus=${corp:-?}"
}

# A crash: the panic with its message, libFuzzer's summary, and the input
# itself in base64 (CI runs in a throw-away clone, where the saved
# artifact is lost with it).
crashed() {
    local t="$1" f="$2" artifact
    echo "fuzz: $t FAILED" >&2
    grep -A1 "panicked at" "$f" >&2 || true
    grep -E "ERROR: libFuzzer|SUMMARY|Test unit written to" "$f" >&2 || tail -30 "$f" >&2
    artifact=$(grep -o 'Test unit written to .*' "$f" | tail -1 | cut -d' ' -f5- || true)
    if [ -n "$artifact" ] && [ -f "$artifact" ] && [ "$(stat -c %s "$artifact")" -le 16384 ]; then
        echo "fuzz: the input, base64 (decode with base64 -d):" >&2
        base64 -w 0 "$artifact" >&2
        echo >&2
    fi
    echo "fuzz: save the input under fuzz/regressions/$t/ once understood" >&2
}

case "$mode" in
smoke)
    ensure_tools
    seconds="${FUZZ_SMOKE_SECONDS:-8}"
    mkdir -p "$log_dir"
    build
    failed=0
    for t in "${targets[@]}"; do
        f="$log_dir/smoke-$t.log"
        start=$(date +%s)
        if run_target "$t" -max_total_time="$seconds" >"$f" 2>&1; then
            echo "fuzz smoke: $t ok in $(($(date +%s) - start)) s: $(figures "$f")"
        else
            crashed "$t" "$f"
            failed=1
        fi
    done
    exit "$failed"
    ;;
long)
    ensure_tools
    runs="${FUZZ_LONG_RUNS:-10000000}"
    seconds="${FUZZ_LONG_SECONDS:-900}"
    mkdir -p "$log_dir"
    build
    summary="$log_dir/long.log"
    echo "# $(date -u +%FT%TZ) long run: -runs=$runs -max_total_time=$seconds, sanitizer $sanitizer, $(nproc) cores" >>"$summary"
    failed=0
    for t in "${targets[@]}"; do
        f="$log_dir/$t.log"
        start=$(date +%s)
        status=ok
        run_target "$t" -runs="$runs" -max_total_time="$seconds" >"$f" 2>&1 || status=FAILED
        line="$t: $status in $(($(date +%s) - start)) s: $(figures "$f")"
        echo "$line" | tee -a "$summary"
        if [ "$status" != ok ]; then
            crashed "$t" "$f"
            failed=1
        fi
    done
    exit "$failed"
    ;;
regressions)
    ensure_tools
    build
    failed=0
    for t in "${targets[@]}"; do
        d="fuzz/regressions/$t"
        [ -d "$d" ] || continue
        for input in "$d"/*; do
            [ -f "$input" ] || continue
            if cargo +nightly fuzz run -s "$sanitizer" "$t" "$input" -- -runs=1 >/dev/null 2>&1; then
                echo "fuzz regressions: $input ok"
            else
                echo "fuzz regressions: $input FAILS" >&2
                failed=1
            fi
        done
    done
    exit "$failed"
    ;;
*)
    echo "usage: bash scripts/fuzz.sh smoke|long|regressions [TARGET...]" >&2
    exit 2
    ;;
esac
