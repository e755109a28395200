"""Issue 30.1 through the real processes (launcher --isolated: fieldsim, relay, backend): the
folders are the launcher's flags and the TOUCHLINE_* environment, shown by GET /api/folders;
a PATCH of a folder is refused naming the field; the recording goes where the command line
said, and nowhere else."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from .conftest import StationHandle, launched, wait_until

JSON = {"content-type": "application/json"}


@pytest.fixture(scope="module")
def folders_station(tmp_path_factory: pytest.TempPathFactory
                    ) -> Iterator[tuple[StationHandle, dict[str, Path]]]:
    base = tmp_path_factory.mktemp("folders")
    where = {"rec": base / "recordings", "scripts": base / "team scripts",
             "logs": base / "old logs"}
    where["scripts"].mkdir()
    where["logs"].mkdir()
    # the log folder from the environment (inherited by the launcher's children), the others
    # from the launcher's command line
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("TOUCHLINE_LOG_DIRS", str(where["logs"]))
        mp.delenv("TOUCHLINE_RECORD_DIR", raising=False)
        mp.delenv("TOUCHLINE_SCRIPTS_DIR", raising=False)
        with launched("--record-dir", str(where["rec"]),
                      "--scripts-dir", str(where["scripts"])) as st:
            yield st, where


def test_get_folders_shows_what_the_station_was_started_with(
        folders_station: tuple[StationHandle, dict[str, Path]]) -> None:
    st, where = folders_station
    folders = {f["name"]: f for f in st.get("/api/folders")["folders"]}
    assert folders["scripts_dir"]["paths"] == [str(where["scripts"])]
    assert folders["record_dir"]["paths"] == [str(where["rec"])]
    assert folders["log_dirs"]["paths"] == [str(where["logs"])]
    assert st.state_dir is not None and folders["state_dir"]["paths"] == [str(st.state_dir)]
    assert {f["flag"] for f in folders.values()} >= {"--scripts-dir", "--record-dir"}
    # the page may open logs of exactly the recording folder and the environment's folder
    assert st.get("/api/logs")["folders"] == [str(where["rec"].resolve()),
                                               str(where["logs"].resolve())]


@pytest.mark.parametrize("change,flag", [
    ({"strategy": {"scripts_dir": "/tmp"}}, "--scripts-dir"),
    ({"recording": {"folder": "/tmp"}}, "--record-dir"),
])
def test_a_patch_of_a_folder_is_refused_with_the_field_named(
        folders_station: tuple[StationHandle, dict[str, Path]], change: dict[str, object],
        flag: str) -> None:
    st, _ = folders_station
    before = st.get("/api/params")
    r = httpx.patch(st.url + "/api/params", json=change, headers=JSON, timeout=10.0)
    assert r.status_code == 422, r.text
    group = next(iter(change))
    key = next(iter(change[group]))  # type: ignore[call-overload]
    [err] = r.json()["detail"]
    assert err["loc"] == ["body", group, key]
    assert err["msg"].startswith(f"folders are set when the station starts ({flag} ")
    assert st.get("/api/params") == before  # nothing applied


def test_the_recording_goes_into_the_folder_of_the_command_line(
        folders_station: tuple[StationHandle, dict[str, Path]]) -> None:
    st, where = folders_station
    rec = wait_until(lambda: (r := st.get("/api/health")["recording"])["recording"] and r, 20,
                     what="recording")
    assert rec["folder"] == str(where["rec"])
    path = where["rec"] / rec["file"]
    wait_until(lambda: path.is_file() and path.stat().st_size > 16, 20,
               what="records written into the file")
    assert [p.name for p in where["rec"].iterdir() if p.name.endswith(".log")] == [rec["file"]]
    # nothing recorded into the state folder's default place
    assert st.state_dir is not None and not (st.state_dir / "logs").exists()
    assert not any(p.suffix == ".log" for p in where["scripts"].iterdir())
    assert os.listdir(where["logs"]) == []
