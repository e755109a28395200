"""The team's code (issue 27): the team folder's files, their states, and editing in the page.

Reading is a viewer's; saving is an operator's on loopback, and from another machine only on
a station started with ``--allow-code-edit`` (``deps.code_editor``; docs/security.md)."""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, HTTPException

from touchline import API_VERSION

from .. import contract
from ..teamcode import files
from .deps import CodeEditorDep, SettingsDep, StationDep, ViewerDep, code_edit_refusal

router = APIRouter(prefix="/api/team", tags=["team"])


@router.get("")
async def team_get(st: StationDep, settings: SettingsDep, caller: ViewerDep) -> contract.TeamCode:
    """The team folder, every file with its state, and whether this caller may edit."""
    why = code_edit_refusal(caller, settings)
    return {"dir": str(settings.team_dir), "api_version": API_VERSION,
            "edit": {"allowed": why is None, "reason": why},
            "files": await st.read(st.team.files_view)}


@router.get("/files/{name:path}")
async def team_file_get(name: str, settings: SettingsDep,
                        _caller: ViewerDep) -> contract.TeamFileText:
    try:
        text, version, language = await asyncio.to_thread(files.read, settings.team_dir, name)
    except files.TeamFileError as exc:
        raise HTTPException(exc.status, exc.detail) from None
    return {"name": name, "text": text, "version": version, "language": language}


@router.put("/files/{name:path}")
async def team_file_put(name: str, body: contract.TeamFileIn, st: StationDep,
                        settings: SettingsDep, caller: CodeEditorDep) -> contract.TeamFileSaved:
    """Saves the file (atomically; 409 when it changed on disk since ``base_version``); the
    station reloads it as after a save from an editor."""
    try:
        version, saved = await asyncio.to_thread(files.save, settings.team_dir, name,
                                                 body.text, body.base_version)
    except files.TeamFileError as exc:
        raise HTTPException(exc.status, exc.detail) from None
    await st.call(st.team_rescan)  # at once, not at the watcher's next look
    await st.call(st.operator_action, "team-save", caller.who,
                  {"file": name, "version": version})
    return {"name": name, "version": version, "saved_at_unix": saved}
