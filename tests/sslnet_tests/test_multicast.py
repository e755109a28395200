import select

import pytest

from sslnet.multicast import (
    loopback_multicast_ok,
    open_multicast_receiver,
    open_multicast_sender,
    open_udp_server,
)


def test_two_receivers_on_one_group_port_both_get_each_datagram() -> None:
    import random

    port = random.randrange(20000, 30000)
    a = open_multicast_receiver("224.5.23.2", port)
    b = open_multicast_receiver("224.5.23.2", port)
    tx = open_multicast_sender()
    try:
        tx.sendto(b"hello", ("224.5.23.2", port))
        for s in (a, b):
            ready, _, _ = select.select([s], [], [], 2.0)
            assert ready and s.recv(64) == b"hello"
    finally:
        for s in (a, b, tx):
            s.close()


def test_a_second_command_server_on_the_same_port_fails_loudly() -> None:
    s = open_udp_server("127.0.0.1", 0)
    try:
        with pytest.raises(OSError):
            open_udp_server("127.0.0.1", s.getsockname()[1])
    finally:
        s.close()


def test_loopback_multicast_check() -> None:
    assert loopback_multicast_ok()
