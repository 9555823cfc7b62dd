"""Rehearsing an outage from the workbench (the Monitor's *Cut the link*):
the simulated link of the ``modd up --simulate`` run this backend watches
(``make run``: its archive directory is ``<workdir>/archive``, its rehearsal
folder ``<workdir>/rehearsal``) cut and restored, as ``modd link cut|restore``
does (``modd.subbroker.rehearsal``). Anyone signed in sees whether it is
available and cut; the operator (or an admin) cuts and restores."""

from __future__ import annotations

import logging
from pathlib import Path as FsPath

from fastapi import APIRouter, Depends
from modd.subbroker.rehearsal import FOLDER, is_cut, set_cut
from pydantic import BaseModel, StrictBool

from ..deps import StateDep, UserDep, require
from ..errors import ApiError
from ..roles import Role
from .archives import Drone

log = logging.getLogger("modd.backend")
router = APIRouter(prefix="/api/drones/{drone}/rehearsal", tags=["live"])
Operator = Depends(require(Role.operator))


class RehearsalIn(BaseModel):
    cut: StrictBool


class RehearsalOut(BaseModel):
    #: The backend watches a simulated run whose link can be cut.
    available: bool
    cut: StrictBool


def _folder(state: StateDep) -> FsPath | None:
    archive = state.settings.archive_dir
    folder = archive.parent / FOLDER if archive is not None else None
    return folder if folder is not None and folder.is_dir() else None


@router.get("")
def rehearsal(drone: Drone, state: StateDep, _user: UserDep) -> RehearsalOut:
    folder = _folder(state)
    return RehearsalOut(available=folder is not None, cut=folder is not None and is_cut(folder))


@router.post("", dependencies=[Operator], responses={409: {"description": "no simulated run"}})
def set_rehearsal(drone: Drone, body: RehearsalIn, state: StateDep, user: UserDep) -> RehearsalOut:
    """Cut (``{"cut": true}``) or restore the simulated link; the SubBroker
    follows within a fifth of a second."""
    folder = _folder(state)
    if folder is None:
        raise ApiError(
            409,
            "no simulated link to cut: this workbench watches no `modd up --simulate` run "
            "(make run); a real drone's link is not cut from here",
        )
    set_cut(folder, body.cut)
    log.warning(
        "rehearsal: %s %s the simulated link of %s",
        user.username,
        "cut" if body.cut else "restored",
        drone,
    )
    return RehearsalOut(available=True, cut=is_cut(folder))
