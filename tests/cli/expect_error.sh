#!/usr/bin/env bash
# Usage: expect_error.sh REGEX COMMAND [ARGS...]
# Passes when COMMAND exits non-zero and prints exactly one line on stderr, matching REGEX.
set -u
regex=$1
shift
err=$(mktemp)
"$@" >/dev/null 2>"$err"
rc=$?
lines=$(wc -l <"$err")
msg=$(cat "$err")
rm -f "$err"
if [ "$rc" -eq 0 ]; then echo "FAIL: exit status 0, expected an error"; exit 1; fi
if [ "$lines" -ne 1 ]; then echo "FAIL: expected one line on stderr, got $lines:"; echo "$msg"; exit 1; fi
if ! grep -qE -- "$regex" <<<"$msg"; then echo "FAIL: '$msg' does not match '$regex'"; exit 1; fi
echo "ok: exit $rc: $msg"
