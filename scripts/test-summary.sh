#!/usr/bin/env bash
# The closing lines of `make test`: which suites did not run, and why (a green run must not
# hide a skipped Octave or multicast suite; under CI those skips already failed the run).
set -euo pipefail
f=test-results/pytest-skipped.txt
echo
echo "== make test: every step passed (ruff, mypy, tsc, pytest, vitest, Playwright)"
if [ -s "$f" ]; then
  echo "!! SUITES THAT DID NOT RUN (pytest):"
  sed 's/^/!!   /' "$f"
else
  echo "   every pytest suite ran, the Octave engine and multicast on loopback included"
fi
