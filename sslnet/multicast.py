"""UDP multicast sockets that behave well on a shared field network.

Receivers set SO_REUSEADDR/SO_REUSEPORT, bind the group port and join the group on a
configured interface address, so several programs (station, ssl-vision-client, game
controller) listen at once. Senders set IP_MULTICAST_IF, IP_MULTICAST_LOOP and a TTL.
"""

from __future__ import annotations

import os
import socket
import struct


def open_multicast_receiver(
    group: str, port: int, interface: str = "127.0.0.1", *, rcvbuf: int = 1 << 21
) -> socket.socket:
    """A non-blocking UDP socket bound to ``port`` that has joined ``group`` on ``interface``."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        if hasattr(socket, "SO_REUSEPORT"):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        # Binding the group address (not INADDR_ANY) keeps unicast and other groups on the
        # same port out of this socket.
        sock.bind((group, port))
        mreq = struct.pack("4s4s", socket.inet_aton(group), socket.inet_aton(interface))
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, mreq)
        sock.setblocking(False)
    except OSError:
        sock.close()
        raise
    return sock


def open_multicast_sender(
    interface: str = "127.0.0.1", *, ttl: int = 1, loop: bool = True
) -> socket.socket:
    """A non-blocking UDP socket that sends multicast out of ``interface``."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    try:
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton(interface))
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, ttl)
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1 if loop else 0)
        sock.setblocking(False)
    except OSError:
        sock.close()
        raise
    return sock


def open_udp_server(host: str, port: int) -> socket.socket:
    """A non-blocking unicast UDP socket bound to ``host:port`` (simulator command ports).

    No SO_REUSEADDR: on Linux it would let a second simulator bind the same UDP port and
    silently share the commands; a clash must fail loudly instead."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    try:
        sock.bind((host, port))
        sock.setblocking(False)
    except OSError:
        sock.close()
        raise
    return sock


IFF_MULTICAST = 0x1000  # linux/if.h


def interface_multicast_flag(name: str = "lo", *, sysfs: str = "/sys/class/net") -> bool | None:
    """Whether interface ``name`` has the MULTICAST flag (``ip link``: ``<LOOPBACK,MULTICAST,UP>``);
    None when that cannot be read (not Linux, no such interface).

    Our own sockets do not need it on lo (they join with the interface address and send with
    IP_MULTICAST_IF, so ``loopback_multicast_ok`` passes without it), but the league's Go
    tools (ssl-vision-client, ssl-game-controller: ssl-go-tools' sslnet) listen only on
    interfaces that have it. A lo without it (a fresh container or network namespace) is
    skipped, and on a machine whose only multicast traffic is on lo they hear nothing.
    """
    try:
        with open(os.path.join(sysfs, name, "flags"), encoding="ascii") as f:
            return bool(int(f.read().strip(), 16) & IFF_MULTICAST)
    except (OSError, ValueError):
        return None


def loopback_multicast_ok() -> bool:
    """True if a multicast datagram sent on 127.0.0.1 comes back to a receiver on lo."""
    import select

    group = "239.255.77.77"
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        rx.bind((group, 0))
        port = rx.getsockname()[1]
        mreq = struct.pack("4s4s", socket.inet_aton(group), socket.inet_aton("127.0.0.1"))
        rx.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, mreq)
        tx = open_multicast_sender("127.0.0.1")
        token = os.urandom(8)
        try:
            tx.sendto(token, (group, port))
        finally:
            tx.close()
        ready, _, _ = select.select([rx], [], [], 0.5)
        return bool(ready) and rx.recv(64) == token
    except OSError:
        return False
    finally:
        rx.close()
