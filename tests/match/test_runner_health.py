"""The match runner's readiness probe: a port that speaks something other than HTTP is "not
ready", never a crash of the runner (a ZeroMQ socket once answered on a backend's port)."""

from __future__ import annotations

import socket
import threading

from match.runner import _health_ok


def test_a_port_answering_a_zeromq_greeting_is_not_healthy_and_does_not_raise() -> None:
    srv = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    srv.bind(("127.0.0.1", 0))
    srv.listen(1)
    port = srv.getsockname()[1]

    def answer() -> None:
        conn, _ = srv.accept()
        with conn:
            conn.recv(4096)
            conn.sendall(b"\xff\x00\x00\x00\x00\x00\x00\x00\x01\x7fvision\r\n\r\n")

    t = threading.Thread(target=answer, daemon=True)
    t.start()
    try:
        assert _health_ok(port) is False
    finally:
        t.join(5.0)
        srv.close()


def test_a_closed_port_is_not_healthy() -> None:
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    assert _health_ok(port) is False
