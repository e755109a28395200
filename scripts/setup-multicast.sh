#!/usr/bin/env bash
# Make multicast work on loopback (DESIGN.md section 2): the built-in simulator, the relay and
# every local tool exchange SSL multicast on lo. Idempotent.
# Our own sockets work on a lo without the MULTICAST flag, but the league's Go tools
# (ssl-vision-client, ssl-game-controller) skip such an interface and hear nothing: set it too.
set -euo pipefail
py=${1:-.venv/bin/python}
ok() { "$py" -c 'from sslnet.multicast import loopback_multicast_ok as ok; raise SystemExit(0 if ok() else 1)'; }
lo_flag() { "$py" -c 'from sslnet.multicast import interface_multicast_flag as f; raise SystemExit(0 if f("lo") is not False else 1)'; }
if ok && lo_flag; then
  exit 0
fi
if [ "$(id -u)" = "0" ] && command -v ip >/dev/null; then
  ip link set lo multicast on
  ip route replace 224.0.0.0/4 dev lo src 127.0.0.1
  if ok; then
    echo "multicast on loopback: lo multicast on, route 224.0.0.0/4 via lo set up"
    exit 0
  fi
elif ok; then
  cat >&2 <<'MSG'
Note: lo has no MULTICAST flag. The station works, but ssl-vision-client and the game controller
skip interfaces without it (with lo the only one they hear nothing). Run once as root:
    ip link set lo multicast on
MSG
  exit 0
fi
cat >&2 <<'MSG'
Multicast on loopback does not work on this machine, and setting it up needs root.
Run once (as root, e.g. with sudo):
    ip link set lo multicast on
    ip route replace 224.0.0.0/4 dev lo src 127.0.0.1
Then run make again. (On a field network, point the station at the LAN interface instead.)
MSG
exit 1
