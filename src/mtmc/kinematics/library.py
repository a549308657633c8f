"""A library of common machine configurations, read from ``library.toml`` (package data).

Examples
--------
>>> "xfyz" in library_names()
True
>>> library_machine("wbzfxyct").topology.chain
('B', 'Z', 'X', 'Y', 'C')
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from typing import Any

from mtmc.document import loads_toml
from mtmc.errors import InputError
from mtmc.kinematics.machine import Machine
from mtmc.kinematics.topology import is_rotary, parse_topology

__all__ = ["LibraryEntry", "library_entries", "library_names", "library_machine"]

_FILE = "library.toml"


@dataclass(frozen=True)
class LibraryEntry:
    """One configuration of the library.

    Parameters
    ----------
    name : str
        Key in the library (``xfyz``, ``table-table`` ...).
    topology : str
        The topology string as written in the file.
    description : str
        One line in words.
    source : str
        Where the configuration comes from (a paper and its equation or figure), or ``""``.
    machine : Machine
        The machine built from the entry (travel of rotary axes converted to rad).
    """

    name: str
    topology: str
    description: str
    source: str
    machine: Machine


def _entry(name: str, raw: dict[str, Any]) -> LibraryEntry:
    where = f"{_FILE}: [{name}]"
    if "topology" not in raw:
        raise InputError(f"{where}: missing key 'topology'", file=_FILE, field=f"{name}.topology")
    topo = parse_topology(str(raw["topology"]))
    travel: dict[str, tuple[float, float]] = {}
    for ax, lim in dict(raw.get("travel", {})).items():
        if not (isinstance(lim, list) and len(lim) == 2):
            raise InputError(
                f"{where}: expected [low, high] for the travel of {ax}",
                file=_FILE,
                field=f"{name}.travel.{ax}",
            )
        lo, hi = float(lim[0]), float(lim[1])
        if is_rotary(ax):
            lo, hi = math.radians(lo), math.radians(hi)
        travel[ax] = (lo, hi)
    machine = Machine.from_topology(
        topo,
        tool=raw.get("tool", (0.0, 0.0, 0.0)),
        workpiece=raw.get("workpiece", (0.0, 0.0, 0.0)),
        pivots=raw.get("pivots", {}),
        travel=travel,
        name=name,
    )
    return LibraryEntry(
        name=name,
        topology=str(raw["topology"]),
        description=str(raw.get("description", "")),
        source=str(raw.get("source", "")),
        machine=machine,
    )


@lru_cache(maxsize=1)
def library_entries() -> tuple[LibraryEntry, ...]:
    """All configurations of the library, in file order.

    Returns
    -------
    tuple of LibraryEntry

    Raises
    ------
    InputError
        If the data file has a malformed entry (naming the entry and key).
    """
    text = resources.files("mtmc.kinematics").joinpath(_FILE).read_text(encoding="utf-8")
    data = loads_toml(text, _FILE).data
    return tuple(_entry(k, v) for k, v in data.items())


def library_names() -> tuple[str, ...]:
    """Names of the library's configurations.

    Returns
    -------
    tuple of str
    """
    return tuple(e.name for e in library_entries())


def library_machine(name: str) -> Machine:
    """The machine of a library configuration.

    Parameters
    ----------
    name : str
        A name from :func:`library_names` (case-insensitive).

    Returns
    -------
    Machine

    Raises
    ------
    InputError
        If there is no such configuration (the message lists the names).
    """
    key = name.strip().lower()
    for e in library_entries():
        if e.name == key:
            return e.machine
    raise InputError(
        f"no machine {name!r} in the library: expected one of {', '.join(library_names())}",
        field="machine",
    )
