#!/usr/bin/env bash
# Make multicast work on loopback (DESIGN.md section 2): the built-in simulator, the relay and
# every local tool exchange SSL multicast on lo. Idempotent.
set -euo pipefail
py=${1:-.venv/bin/python}
if "$py" -c 'from sslnet.multicast import loopback_multicast_ok as ok; raise SystemExit(0 if ok() else 1)'; then
  exit 0
fi
if [ "$(id -u)" = "0" ] && command -v ip >/dev/null; then
  ip link set lo multicast on
  ip route replace 224.0.0.0/4 dev lo src 127.0.0.1
  if "$py" -c 'from sslnet.multicast import loopback_multicast_ok as ok; raise SystemExit(0 if ok() else 1)'; then
    echo "multicast on loopback: route 224.0.0.0/4 via lo set up"
    exit 0
  fi
fi
cat >&2 <<'MSG'
Multicast on loopback does not work on this machine, and setting it up needs root.
Run once (as root, e.g. with sudo):
    ip link set lo multicast on
    ip route replace 224.0.0.0/4 dev lo src 127.0.0.1
Then run make again. (On a field network, point the station at the LAN interface instead.)
MSG
exit 1
