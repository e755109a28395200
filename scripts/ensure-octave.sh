#!/usr/bin/env bash
# The compute engine's Octave backend runs a team's .m scripts with Debian's GNU Octave.
set -euo pipefail
if command -v octave-cli >/dev/null; then exit 0; fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends octave >/dev/null
  exit 0
fi
echo "octave-cli is missing: install Debian's octave (apt-get install -y octave) as root;" \
     "the Octave engine tests are skipped without it" >&2
exit 0
