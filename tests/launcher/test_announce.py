"""The launcher's machine-readable lines (TOUCHLINE_READY ...) reach a shared pipe whole."""

from __future__ import annotations

import io

from launcher.__main__ import announce


class _Writes(io.StringIO):
    def __init__(self) -> None:
        super().__init__()
        self.calls: list[str] = []

    def write(self, s: str) -> int:
        self.calls.append(s)
        return super().write(s)


def test_a_line_is_one_write_with_its_newline() -> None:
    # print() writes the text and the newline apart: on an unbuffered pipe shared with the
    # children a child's log line could land between them (it did: "TOUCHLINE_READY
    # http://127.0.0.1:48805<a log line>")
    out = _Writes()
    announce("TOUCHLINE_READY http://127.0.0.1:8000", out)
    assert out.calls == ["TOUCHLINE_READY http://127.0.0.1:8000\n"]

