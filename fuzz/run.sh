#!/usr/bin/env bash
# Runs every fuzz target for SECONDS each (default 30), one after another, on the committed
# corpus (copied to fuzz/corpus-work/, so the committed corpus stays minimal), and prints
# libFuzzer's final line (executions, coverage) per target. Needs `cargo +nightly` and
# cargo-fuzz (`cargo install cargo-fuzz`). Exit status non-zero when a target crashed; the
# crashing input is in fuzz/artifacts/<target>/. Built without a sanitizer: the crates are safe
# Rust (panics, overflows and debug assertions are caught without one), and AddressSanitizer made
# the ground-station harness (a reader thread per input) 400 times slower.
#   fuzz/run.sh 600          # ten minutes each
#   fuzz/run.sh 30 imagemap  # one target
set -euo pipefail
cd "$(dirname "$0")"
seconds=${1:-30}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(colliders movingai imagemap plan_request mavlink_sim mavlink_ground dem)
nice -n 19 cargo +nightly fuzz build --sanitizer none >/dev/null
failed=0
for t in "${targets[@]}"; do
  mkdir -p "corpus-work/$t" "artifacts/$t"
  cp -n "corpus/$t"/* "corpus-work/$t"/ 2>/dev/null || true
  log="corpus-work/$t.log"
  if nice -n 19 cargo +nightly fuzz run --sanitizer none "$t" "corpus-work/$t" "corpus/$t" -- \
      -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
      -artifact_prefix="artifacts/$t/" -print_final_stats=1 >"$log" 2>&1; then
    status=ok
  else
    status=CRASH
    failed=1
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
  last=$(grep -E '^#[0-9]+' "$log" | tail -n 1 || true)
  echo "fuzz $t: $status, ${seconds} s, $execs executions; last: $last"
done
exit "$failed"
