"""Any bytes after a valid header: LogFile either opens (and streams) or raises
LogFormatError; never another exception."""

import tempfile
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from ssllog.logfile import LogFile
from ssllog.reader import LogFormatError
from tests.ssllog.test_logfile import HEAD, T0, rec, wrapper

VALID = HEAD + rec(T0, 4, wrapper(0, 1)) + rec(T0 + 1, 3, b"\x08\x01")


@settings(max_examples=300, deadline=None)
@given(tail=st.binary(max_size=300), cut=st.integers(0, len(VALID)))
def test_garbage_opens_or_raises_log_format_error(tail: bytes, cut: int) -> None:
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "g.log"
        p.write_bytes(VALID[:cut] + tail)
        try:
            with LogFile.open(str(p), Path(d) / "c") as lf:
                for r in lf.records(include_unknown=True):
                    lf.prev_record_offset(r.offset, 4)
                lf.offset_at(T0)
        except LogFormatError:
            pass
