#!/usr/bin/env bash
# phex — runs each fuzz target for FUZZ_SECONDS (make fuzz; make test runs it briefly). Each starts from its
# seeds (tests/fuzz/corpus/TARGET) and the files fuzzing found (tests/fuzz/regressions), keeps what it
# learns in build/fuzz/corpus/TARGET (or FUZZ_CORPUS/TARGET), and writes a finding to build/fuzz/findings/;
# any finding fails the run.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="$here/../../build/fuzz"
seconds="${FUZZ_SECONDS:-60}"
corpus="${FUZZ_CORPUS:-$build/corpus}"  # what runs learn; make test starts from an empty one, to stay short
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(read_obj read_off read_ply read_stl mesh_surface pipeline)
mkdir -p "$build/findings"
failed=()
for t in "${targets[@]}"; do
  mkdir -p "$corpus/$t"
  # A hang is an input over 30 s, or 120 s for the whole pipeline: sanitized, it runs some 60 times slower than
  # natively (the refusal of a flat two-sided needle by the global method: 1.0 s native, 59 s sanitized).
  timeout=30
  [ "$t" = pipeline ] && timeout=120
  options=(-max_total_time="$seconds" -timeout="$timeout" -rss_limit_mb=2048 -max_len=4096 -print_final_stats=1
           -artifact_prefix="$build/findings/$t-")
  # Readers take files: their keywords help; the others take structured bytes (fuzz.hpp).
  case "$t" in read_*) options+=(-dict="$here/mesh.dict") ;; esac
  log="$build/$t-$$.log"  # one per run: a campaign and make test may fuzz at the same time
  if nice "$build/fuzz_$t" "${options[@]}" "$corpus/$t" "$here/corpus/$t" "$here/regressions" >"$log" 2>&1; then
    status=ok
  else
    status=FINDING
    failed+=("$t")
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1 || true)
  printf '%-13s %s  %s executions in %ss, %s  (%s)\n' "$t" "$status" "$runs" "$seconds" "$cov" "${log#"$here/../../"}"
done
if [ ${#failed[@]} -gt 0 ]; then
  for t in "${failed[@]}"; do echo "== $t"; grep -A25 -m1 'ERROR\|phex fuzz finding\|==.*==' "$build/$t-$$.log" | head -40; done
  echo "fuzzing found something in: ${failed[*]} (inputs in build/fuzz/findings/)"
  exit 1
fi
