#!/usr/bin/env bash
# One short libFuzzer run (ctest's fuzz.<target>): the checked-in corpus, then SECONDS of mutation.
# New inputs go to SCRATCH/new, a crash, leak or hang to SCRATCH/ (its path is printed); the
# checked-in corpus is read, never written. Exits non-zero on any finding.
# Usage: run.sh FUZZER CORPUS_DIR SCRATCH_DIR SECONDS
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
fuzzer="$1" corpus="$2" scratch="$3" seconds="$4"
[ -x "$fuzzer" ] || { echo "no fuzz target $fuzzer (fuzz.build builds it)" >&2; exit 1; }
rm -rf "$scratch"
mkdir -p "$scratch/new"
# Leaks inside assimp (on malformed files) are not ours to fix; every other leak is a finding.
export LSAN_OPTIONS="suppressions=$here/lsan.supp:print_suppressions=0"
# Anything a target writes to the temporary folder stays under SCRATCH.
export TMPDIR="$scratch"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
exec "$fuzzer" -max_total_time="$seconds" -timeout=25 -rss_limit_mb=2048 -max_len=4096 \
  -print_final_stats=1 -artifact_prefix="$scratch/" "$scratch/new" "$corpus"
