"""The backend's process keeps its start-up objects out of the garbage collector
(Settings.freeze_gc, set by ``python -m backend``): a full collection then looks only at what
came later instead of the ~105 000 objects of a full-scale station (65 ms of CPU holding the
GIL, the station's pass waiting). A test process with many stations does not freeze."""

from __future__ import annotations

import gc
from pathlib import Path

from backend.config import Settings
from backend.station import Station
from launcher.supervisor import free_tcp_port


def _station(tmp_path: Path, freeze: bool) -> Station:
    return Station(Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                            relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                            state_dir=tmp_path / "state", record=False, freeze_gc=freeze))


def test_start_up_objects_frozen_only_when_asked(tmp_path: Path) -> None:
    gc.unfreeze()
    st = _station(tmp_path / "a", freeze=False)
    st.start_thread()
    try:
        assert gc.get_freeze_count() == 0
    finally:
        st.stop_thread()
    st = _station(tmp_path / "b", freeze=True)
    try:
        st.start_thread()
        # the station's own objects are in the permanent generation: a full collection
        # does not visit them
        frozen = gc.get_freeze_count()
        assert frozen > 1000, frozen
        assert not any(o is st for o in gc.get_objects())
        assert not any(o is st.world for o in gc.get_objects())
    finally:
        st.stop_thread()
        gc.unfreeze()  # the rest of the test session collects as usual
