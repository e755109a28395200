"""The latched emergency stop's file (backend.estop): what survives a restart, what a broken
or missing file means (a pressed stop where in doubt), and a folder that cannot be written."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from backend.api import create_app
from backend.config import Settings
from backend.estop import EstopLatch
from backend.station import Station
from launcher.supervisor import free_tcp_port


def test_a_press_survives_a_restart_and_only_a_release_ends_it(tmp_path: Path) -> None:
    latch = EstopLatch(tmp_path)
    assert not latch.active and not (tmp_path / "estop.json").exists()
    latch.set(True, "operator at 127.0.0.1")
    on_disk = json.loads((tmp_path / "estop.json").read_text())
    assert on_disk["active"] is True and on_disk["by"] == "operator at 127.0.0.1"
    assert [p.name for p in tmp_path.iterdir()] == ["estop.json"]  # no temporary file left

    again = EstopLatch(tmp_path)  # a fresh backend on the same state folder
    assert again.active and again.state.by == "operator at 127.0.0.1"
    assert again.state.since == pytest.approx(latch.state.since)
    again.set(False, "operator at 10.0.0.2")
    assert not EstopLatch(tmp_path).active


def test_no_state_folder_keeps_the_stop_in_memory() -> None:
    latch = EstopLatch(None)
    latch.set(True, "x")
    assert latch.active and latch.warning == ""


@pytest.mark.parametrize("content", [
    "{not json", "[]", '{"since": 1}', '{"active": null}', '{"active": "false"}',
    '{"active": 0}', '"active"', "\udcff",
])
def test_a_file_that_does_not_say_released_is_a_pressed_stop(tmp_path: Path,
                                                            content: str) -> None:
    (tmp_path / "estop.json").write_bytes(content.encode("utf-8", "surrogateescape"))
    latch = EstopLatch(tmp_path)
    assert latch.active, content
    assert "not readable" in latch.warning


def test_a_folder_in_place_of_the_file_is_a_pressed_stop(tmp_path: Path) -> None:
    (tmp_path / "estop.json").mkdir()
    assert EstopLatch(tmp_path).active


def test_a_folder_that_cannot_be_written_is_said_and_the_stop_holds(tmp_path: Path) -> None:
    (tmp_path / "state").write_text("a file where the state folder belongs")
    latch = EstopLatch(tmp_path / "state")
    latch.set(True, "x")
    assert latch.active and "not persisted" in latch.warning


def test_a_fresh_backend_with_a_persisted_stop_says_so_in_health_and_to_every_page(
        tmp_path: Path) -> None:
    state = tmp_path / "state"
    EstopLatch(state).set(True, "operator at 10.0.0.9")  # pressed under an earlier backend
    settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=state, allowed_hosts=["testserver"])
    st = Station(settings)
    with TestClient(create_app(settings, st), headers={"X-Touchline": "1"}) as c:
        h = c.get("/api/health").json()
        assert h["estop"]["active"] is True and h["estop"]["by"] == "operator at 10.0.0.9"
        assert h["estop"]["relay_latched"] is None  # no relay statistics yet
        active = [w for w in h["warnings"] if w.startswith("emergency stop active since")]
        assert len(active) == 1 and "operator at 10.0.0.9" in active[0]
        with c.websocket_connect("/api/ws") as ws:
            snap = json.loads(ws.receive_text())
            assert snap["health"]["estop"]["active"] is True
            assert snap["world"]["estop"] is True

        # a relay that reports no latch long after the press is a problem worth a line
        def relay_without_latch() -> None:  # through the station: its one writer
            st.relay_stats.write({"estop_latched": False, "estop_by": "",
                                  "received_mono": time.monotonic(), "streams": {}})
            st.safety.estop_mono = time.monotonic() - 10
        st.call_sync(relay_without_latch)
        h = c.get("/api/health").json()
        assert h["estop"]["relay_latched"] is False
        assert any("relay has not latched" in w for w in h["warnings"]), h["warnings"]

        assert c.post("/api/estop", json={"active": False, "confirm": True}).status_code == 200
        h = c.get("/api/health").json()
        assert h["estop"]["active"] is False
        assert not any("emergency stop" in w for w in h["warnings"]), h["warnings"]
